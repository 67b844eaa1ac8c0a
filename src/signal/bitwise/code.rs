//! The code replica as words: a byte table expands C/A chips into samples, eight samples per
//! lookup, anchored every byte to the exact 32.32 code NCO.
//!
//! # The replica this realizes
//! For word `w` (block samples `32w … 32w + 31`) let `P_w` be the code NCO's prompt phase at
//! sample `32w` (2⁻³² chip, reduced to `[0, 1023·2³²)`), `c₀ = ⌊P_w/2³²⌋` and
//! `f = P_w mod 2³²`. Byte `g` (samples `32w + 8g + i`, `i = 0..7`) is anchored at
//! `ℓ_g = ⌊f/2⁵⌋ + g·⌊s/4⌋` (units of 2⁻²⁷ chip, `s` = code step per sample), whose integer
//! part `j_g = ⌊ℓ_g/2²⁷⌋` and top fraction bits `q_g = ⌊ℓ_g/2¹⁹⌋ mod 256` select the chip
//! `c₀ + j_g + o(q_g, i)` for sample `i`, with
//!
//! ```text
//! o(q, i) = ⌊((q + ½)·2²⁴ + i·s_t) / 2³²⌋        (s_t: the table's step, 2⁻³² chip/sample)
//! ```
//!
//! i.e. the code phase of the sample is the byte's anchor rounded to the middle of its
//! 1/256-chip bin plus `i` table steps. The table step is the nominal `f_chip/f_s`; the anchor
//! follows the NCO exactly every eight samples, so the replica differs from the exact
//! per-sample phase by at most `1/512` chip plus `7·|s − s_t|` (1.5·10⁻⁴ chip at a code
//! Doppler of 5·10⁻⁵; the correlator refuses code rates more than 1 % off nominal, where the
//! bound is 0.03 chip). Chip values are the C/A signs (logic 1 = −1, as a set bit).
//!
//! # Cost
//! Per word: the 32-chip window at `c₀` (two loads and a funnel shift) and four lookups
//! (index = `q_g · 32 + (window ≫ j_g) & 31`). The table is 8 KiB per sample rate, shared by
//! every correlator of a front end: [`CodeTable`].

use super::correlator::BitCorrelatorError;
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ, CA_CODE_LENGTH};
use crate::signal::nco::{CodeNco, CODE_WRAP};

/// Fraction bits of the byte anchor that index the table (1/256-chip bins).
pub const CODE_TABLE_FRACTION_BITS: u32 = 8;

/// Chips a table entry reads (the byte's samples span at most five chips for a step below
/// 4/7 chip per sample).
pub const CODE_TABLE_CHIPS: u32 = 5;

/// Entries of the table.
pub const CODE_TABLE_LEN: usize = 1 << (CODE_TABLE_FRACTION_BITS + CODE_TABLE_CHIPS);

/// Smallest sample rate the byte table supports, Hz (two samples per chip).
pub const MIN_TABLE_SAMPLE_RATE_HZ: f64 = 2.0 * CA_CHIP_RATE_HZ;

/// Bytes of the extended code: chips `0 … 8·EXT_BYTES − 1`, chip `c` = code chip
/// `c mod 1023` (bit `c mod 8` of byte `c / 8`), read as unaligned little-endian words.
pub(crate) const EXT_BYTES: usize = 136;

/// The chip-to-sample expansion table of one sample rate (8 KiB), shared by the correlators of
/// a front end. Entry `q·32 + chips` holds, in bit `i`, bit `o(q, i)` of `chips` (see the
/// module documentation).
#[derive(Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CodeTable {
    step: u64,
    bytes: [u8; CODE_TABLE_LEN],
}

impl CodeTable {
    /// The table for `sample_rate_hz`, at the nominal chip rate.
    ///
    /// # Errors
    /// [`BitCorrelatorError::InvalidConfig`] for a rate outside
    /// `[MIN_TABLE_SAMPLE_RATE_HZ, MAX_SAMPLE_RATE_HZ]` or non-finite.
    pub fn new(sample_rate_hz: f64) -> Result<Self, BitCorrelatorError> {
        let max = crate::signal::correlator::MAX_SAMPLE_RATE_HZ;
        if !(MIN_TABLE_SAMPLE_RATE_HZ..=max).contains(&sample_rate_hz) {
            return Err(BitCorrelatorError::InvalidConfig);
        }
        Ok(Self::from_step(CodeNco::step_for(
            CA_CHIP_RATE_HZ,
            sample_rate_hz,
        )))
    }

    /// The table for a code step of `step` (2⁻³² chip per sample), at compile time if wanted.
    /// Steps above 4/7 chip per sample would need more chips per entry; they are clamped to
    /// the largest supported step (use [`CodeTable::new`], which validates the rate).
    pub const fn from_step(step: u64) -> Self {
        const MAX_STEP: u64 = (4u64 << 32) / 7;
        let step = if step > MAX_STEP { MAX_STEP } else { step };
        let mut bytes = [0u8; CODE_TABLE_LEN];
        let mut q = 0u64;
        while q < 1 << CODE_TABLE_FRACTION_BITS {
            let mut chips = 0u64;
            while chips < 1 << CODE_TABLE_CHIPS {
                let mut v = 0u8;
                let mut i = 0u64;
                while i < 8 {
                    let o = expansion_offset(q, i, step);
                    v |= (((chips >> o) & 1) as u8) << i;
                    i += 1;
                }
                bytes[((q << CODE_TABLE_CHIPS) | chips) as usize] = v;
                chips += 1;
            }
            q += 1;
        }
        Self { step, bytes }
    }

    /// The table's code step, 2⁻³² chip per sample.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// The entry for fraction bin `q` and chip window `chips`.
    #[inline(always)]
    pub(crate) fn entry(&self, q: u32, chips: u32) -> u32 {
        let index = (((q & 0xff) << CODE_TABLE_CHIPS) | (chips & 31)) as usize;
        u32::from(self.bytes[index & (CODE_TABLE_LEN - 1)])
    }
}

/// `o(q, i)`: the chip offset of sample `i` of a byte anchored in fraction bin `q`.
pub const fn expansion_offset(q: u64, i: u64, table_step: u64) -> u64 {
    ((q << 24) + (1 << 23) + i * table_step) >> 32
}

/// The code of `prn` repeated: bit `c` of the result is the logic value of chip `c mod 1023`.
pub(crate) fn extended_code(prn: Prn) -> [u8; EXT_BYTES] {
    let mut out = [0u8; EXT_BYTES];
    for c in 0..EXT_BYTES * 8 {
        let bit = prn.chip_bit(c % CA_CODE_LENGTH);
        if let Some(b) = out.get_mut(c / 8) {
            *b |= bit << (c % 8);
        }
    }
    out
}

/// `x mod CODE_WRAP`, without a 64-bit division (a library call on the Cortex-M4) for
/// `x < 2·CODE_WRAP`, the phases the word loop meets.
#[inline(always)]
pub(crate) fn wrap_code(x: u64) -> u64 {
    if x < CODE_WRAP {
        x
    } else if x < 2 * CODE_WRAP {
        x - CODE_WRAP
    } else {
        x % CODE_WRAP
    }
}

/// The code NCO's state at a word start, split for the word loop: chip index `chip`
/// (`0 … 1022`) and fraction `frac` (2⁻³² chip).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct CodeCursor {
    pub(crate) chip: u32,
    pub(crate) frac: u32,
}

impl CodeCursor {
    /// From a phase in `[0, CODE_WRAP)`.
    #[inline(always)]
    pub(crate) fn from_phase(phase: u64) -> Self {
        let phase = wrap_code(phase);
        Self {
            chip: (phase >> 32) as u32,
            frac: phase as u32,
        }
    }

    /// Advances by `step32` (a step of 32 samples, split into chips and fraction, chips below
    /// 1023), wrapping at the code period.
    #[inline(always)]
    pub(crate) fn advance(&mut self, chips: u32, frac: u32) {
        let (f, carry) = self.frac.overflowing_add(frac);
        // (chip < 1023 plus a word's few chips: far from wrapping)
        let c = self.chip.wrapping_add(chips).wrapping_add(u32::from(carry));
        self.frac = f;
        self.chip = if c >= CA_CODE_LENGTH as u32 {
            c - CA_CODE_LENGTH as u32
        } else {
            c
        };
    }
}

/// The prompt code word (bit `k` = logic chip value at sample `k` of the word) for the word
/// whose first sample has code phase `at`; `step4 = ⌊s/4⌋`.
#[inline(always)]
pub(crate) fn prompt_word(
    ext: &[u8; EXT_BYTES],
    table: &CodeTable,
    at: CodeCursor,
    step4: u32,
) -> u32 {
    let c0 = (at.chip as usize) & 1023;
    // Chips c0 … c0 + 24 (the byte windows need at most c0 + 18): an unaligned word from the
    // byte holding chip c0.
    let bytes = match ext.get(c0 / 8..c0 / 8 + 4) {
        Some(&[a, b, c, d]) => [a, b, c, d],
        _ => [0; 4],
    };
    let window = u32::from_le_bytes(bytes) >> (c0 % 8);
    let mut anchor = at.frac >> 5;
    let mut word = 0u32;
    for g in 0..4 {
        let j = anchor >> 27;
        let q = anchor >> 19;
        word |= table.entry(q, window >> j) << (8 * g);
        anchor = anchor.wrapping_add(step4);
    }
    word
}

/// The logic chip value that the word replica gives sample `k` (0–31) of a word whose first
/// sample has code phase `phase` (a per-sample evaluation of the definition in the module
/// documentation, for the scalar reference).
pub fn replica_chip(prn: Prn, phase: u64, step: u64, table_step: u64, k: usize) -> u8 {
    let at = CodeCursor::from_phase(phase);
    let g = (k / 8) as u32;
    let i = (k % 8) as u64;
    let step4 = (step >> 2) as u32;
    let anchor = (at.frac >> 5).wrapping_add(g.wrapping_mul(step4));
    let j = u64::from(anchor >> 27);
    let q = u64::from((anchor >> 19) & 0xff);
    let chip = u64::from(at.chip) + j + expansion_offset(q, i, table_step);
    prn.chip_bit((chip % CA_CODE_LENGTH as u64) as usize)
}

/// Validation of a code step for the word replica.
pub(crate) fn step_supported(step: u64) -> Result<(), BitCorrelatorError> {
    // Below 4/7 chip per sample (the table's reach), and positive.
    if step == 0 || step > (4u64 << 32) / 7 {
        return Err(BitCorrelatorError::InvalidConfig);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_entries_follow_the_definition() {
        let t = CodeTable::new(2.6e6).unwrap();
        for q in [0u32, 1, 100, 255] {
            for chips in 0..32u32 {
                let e = t.entry(q, chips);
                for i in 0..8 {
                    let o = expansion_offset(u64::from(q), i, t.step());
                    assert!(o <= 4);
                    assert_eq!((e >> i) & 1, (chips >> o) & 1);
                }
            }
        }
    }

    #[test]
    fn prompt_words_follow_the_per_sample_definition() {
        let prn = Prn::new(7).unwrap();
        let ext = extended_code(prn);
        for fs in [2.046e6, 2.6e6, 4.092e6, 16.368e6] {
            let t = CodeTable::new(fs).unwrap();
            let step = CodeNco::step_for(CA_CHIP_RATE_HZ * (1.0 + 3e-5), fs);
            let mut phase = CodeNco::phase_for(1019.3);
            for _ in 0..200 {
                let w = prompt_word(&ext, &t, CodeCursor::from_phase(phase), (step >> 2) as u32);
                for k in 0..32 {
                    let want = replica_chip(prn, phase, step, t.step(), k);
                    assert_eq!((w >> k) & 1, u32::from(want), "fs {fs} k {k}");
                }
                phase = (phase + 32 * step) % CODE_WRAP;
            }
        }
    }

    #[test]
    fn replica_is_within_its_bound_of_the_exact_code() {
        // Away from chip edges (farther than the bound), the replica chip is the exact one.
        let prn = Prn::new(3).unwrap();
        let fs = 2.6e6;
        let t = CodeTable::new(fs).unwrap();
        let step = CodeNco::step_for(CA_CHIP_RATE_HZ * (1.0 - 4e-5), fs);
        let bound = 1.0 / 512.0 + 7.0 * (step as f64 - t.step() as f64).abs() / 4_294_967_296.0;
        let mut phase = CodeNco::phase_for(3.7);
        let mut checked = 0;
        for _ in 0..100 {
            for k in 0..32u64 {
                let exact = (phase + k * step) as f64 / 4_294_967_296.0;
                let frac = exact - exact.floor();
                if frac > bound + 1e-9 && frac < 1.0 - bound - 1e-9 {
                    let chip = (exact.floor() as usize) % CA_CODE_LENGTH;
                    let got = replica_chip(prn, phase, step, t.step(), k as usize);
                    assert_eq!(got, prn.chip_bit(chip));
                    checked += 1;
                }
            }
            phase = (phase + 32 * step) % CODE_WRAP;
        }
        assert!(checked > 3000);
    }
}
