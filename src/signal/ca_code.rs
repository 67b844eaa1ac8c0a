//! GPS L1 C/A codes (IS-GPS-200, §3.3.2.3): the 1023-chip Gold codes of PRN 1–32.
//!
//! Each code is the modulo-2 sum of two 10-stage maximal-length sequences clocked at 1.023 MHz,
//! both registers starting all ones:
//!
//! * `G1 = 1 + x³ + x¹⁰` (feedback from stages 3 and 10; output stage 10),
//! * `G2 = 1 + x² + x³ + x⁶ + x⁸ + x⁹ + x¹⁰` (feedback from stages 2, 3, 6, 8, 9, 10); the
//!   PRN-specific output is the sum of two G2 stages (the *phase selector* taps of IS-GPS-200
//!   Table 3-Ia, [`G2_TAPS`]), which delays G2 by the PRN's "G2 delay".
//!
//! The codes are computed by `const fn` at compile time into [`CA_CODE_BITS`] (4 KiB: 32 words
//! of 32 bits per PRN, chip `k` is bit `k % 32` of word `k / 32`). A chip's *logic* value is the
//! bit; its *signal* value is `+1` for logic 0 and `−1` for logic 1 (the usual mapping, under
//! which the modulo-2 sum becomes a product).

/// Chips in one C/A code period.
pub const CA_CODE_LENGTH: usize = 1023;

/// Nominal C/A chip rate, chips per second.
pub const CA_CHIP_RATE_HZ: f64 = 1.023e6;

/// GPS L1 carrier frequency, Hz (1540 chips of carrier per code chip).
pub const GPS_L1_HZ: f64 = 1_575.42e6;

/// Number of PRNs with a C/A code here (1–32).
pub const PRN_COUNT: usize = 32;

/// Words of 32 bits that hold one packed code (1023 chips, the last bit unused and 0).
pub const CODE_WORDS: usize = 32;

/// IS-GPS-200 Table 3-Ia: the two G2 stages (1-based) whose sum is the G2 output of each PRN,
/// index `prn − 1`.
pub const G2_TAPS: [(u8, u8); PRN_COUNT] = [
    (2, 6),
    (3, 7),
    (4, 8),
    (5, 9),
    (1, 9),
    (2, 10),
    (1, 8),
    (2, 9),
    (3, 10),
    (2, 3),
    (3, 4),
    (5, 6),
    (6, 7),
    (7, 8),
    (8, 9),
    (9, 10),
    (1, 4),
    (2, 5),
    (3, 6),
    (4, 7),
    (5, 8),
    (6, 9),
    (1, 3),
    (4, 6),
    (5, 7),
    (6, 8),
    (7, 9),
    (8, 10),
    (1, 6),
    (2, 7),
    (3, 8),
    (4, 9),
];

/// The C/A code of `prn` (1–32) as packed logic bits, by running the two shift registers
/// (`const fn`: evaluated at compile time for [`CA_CODE_BITS`]). An out-of-range PRN gives
/// all zeros.
pub const fn generate_code_bits(prn: u8) -> [u32; CODE_WORDS] {
    let mut out = [0u32; CODE_WORDS];
    if prn == 0 || prn as usize > PRN_COUNT {
        return out;
    }
    let (t1, t2) = G2_TAPS[prn as usize - 1];
    // Stage s (1-based) is bit s − 1 of each register.
    let mut g1: u16 = 0x3ff;
    let mut g2: u16 = 0x3ff;
    let mut k = 0;
    while k < CA_CODE_LENGTH {
        let g1_out = (g1 >> 9) & 1;
        let g2_out = ((g2 >> (t1 - 1)) ^ (g2 >> (t2 - 1))) & 1;
        let chip = (g1_out ^ g2_out) as u32;
        out[k / 32] |= chip << (k % 32);
        // Shift towards stage 10; the feedback enters stage 1.
        let f1 = ((g1 >> 2) ^ (g1 >> 9)) & 1;
        let f2 = ((g2 >> 1) ^ (g2 >> 2) ^ (g2 >> 5) ^ (g2 >> 7) ^ (g2 >> 8) ^ (g2 >> 9)) & 1;
        g1 = ((g1 << 1) | f1) & 0x3ff;
        g2 = ((g2 << 1) | f2) & 0x3ff;
        k += 1;
    }
    out
}

const fn generate_all() -> [[u32; CODE_WORDS]; PRN_COUNT] {
    let mut all = [[0u32; CODE_WORDS]; PRN_COUNT];
    let mut p = 0;
    while p < PRN_COUNT {
        all[p] = generate_code_bits(p as u8 + 1);
        p += 1;
    }
    all
}

/// All 32 C/A codes as packed logic bits, index `prn − 1`; computed at compile time.
pub static CA_CODE_BITS: [[u32; CODE_WORDS]; PRN_COUNT] = generate_all();

const fn signs_all() -> [[i8; 1024]; PRN_COUNT] {
    let mut all = [[0i8; 1024]; PRN_COUNT];
    let mut p = 0;
    while p < PRN_COUNT {
        let bits = generate_code_bits(p as u8 + 1);
        let mut k = 0;
        while k < CA_CODE_LENGTH {
            all[p][k] = 1 - 2 * ((bits[k / 32] >> (k % 32)) & 1) as i8;
            k += 1;
        }
        // Entry 1023 repeats chip 0 (never read by a correct index; keeps `& 1023` safe).
        all[p][CA_CODE_LENGTH] = all[p][0];
        p += 1;
    }
    all
}

/// All 32 C/A codes as signal values (`±1`, one `i8` per chip, 1024 entries per PRN so that
/// an index masked with `& 1023` is always in bounds), index `prn − 1`; computed at compile
/// time (32 KiB of read-only data). The correlator's replica generator reads it.
pub static CA_CODE_SIGNS: [[i8; 1024]; PRN_COUNT] = signs_all();

/// A PRN number validated to be in 1–32.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Prn(u8);

impl Prn {
    /// PRN 1.
    pub const FIRST: Self = Self(1);

    /// `Some` for 1–32.
    pub const fn new(prn: u8) -> Option<Self> {
        if prn >= 1 && prn as usize <= PRN_COUNT {
            Some(Self(prn))
        } else {
            None
        }
    }

    /// The PRN number, 1–32.
    pub const fn number(self) -> u8 {
        self.0
    }

    /// Index into per-PRN tables, 0–31.
    pub const fn index(self) -> usize {
        // (1–32 by construction; wrapping keeps the mask's result for any value)
        (self.0 as usize).wrapping_sub(1) & (PRN_COUNT - 1)
    }

    /// The packed code bits of this PRN.
    pub fn code_bits(self) -> &'static [u32; CODE_WORDS] {
        &CA_CODE_BITS[self.index()]
    }

    /// The ±1 chip table of this PRN (see [`CA_CODE_SIGNS`]).
    pub fn code_signs(self) -> &'static [i8; 1024] {
        &CA_CODE_SIGNS[self.index()]
    }

    /// Logic value (0 or 1) of chip `k` (taken modulo 1024, so `k` must be below 1023 for a
    /// meaningful chip; chip 1023 reads as 0).
    #[inline(always)]
    pub fn chip_bit(self, k: usize) -> u8 {
        let words = self.code_bits();
        ((words[(k >> 5) & (CODE_WORDS - 1)] >> (k & 31)) & 1) as u8
    }

    /// Signal value (+1 for logic 0, −1 for logic 1) of chip `k`, `k < 1023`.
    #[inline(always)]
    pub fn chip(self, k: usize) -> i8 {
        1 - 2 * self.chip_bit(k) as i8
    }

    /// The first ten chips as the octal number IS-GPS-200 Table 3-Ia prints (first chip is the
    /// most significant bit).
    pub fn first_ten_chips_octal(self) -> u16 {
        let mut v = 0u16;
        for k in 0..10 {
            v = (v << 1) | u16::from(self.chip_bit(k));
        }
        v
    }
}

/// The autocorrelation (`a = b`) or cross-correlation of two codes at a cyclic shift of
/// `shift` chips: `Σ_k c_a[k] · c_b[(k + shift) mod 1023]`, in chips (1023 at the peak).
pub fn cyclic_correlation(a: Prn, b: Prn, shift: usize) -> i32 {
    let shift = shift % CA_CODE_LENGTH;
    let mut sum = 0i32;
    for k in 0..CA_CODE_LENGTH {
        let mut j = k + shift;
        if j >= CA_CODE_LENGTH {
            j -= CA_CODE_LENGTH;
        }
        sum += i32::from(a.chip(k)) * i32::from(b.chip(j));
    }
    sum
}

/// A code offset (chips) at which the PRN's autocorrelation is `−1` at both neighbouring
/// integer shifts, so that a tap placed half-way between them sees no signal (−60 dB): the
/// correlator's noise tap uses it. The smallest such offset from 6 chips up (bounded search:
/// at most 64 offsets; IS-GPS-200 codes all have one below 16).
pub const fn quiet_offset_chips(prn: u8) -> u16 {
    let bits = generate_code_bits(prn);
    let mut shift = 6usize;
    while shift < 70 {
        if autocorrelation_const(&bits, shift) == -1
            && autocorrelation_const(&bits, shift + 1) == -1
        {
            return shift as u16;
        }
        shift += 1;
    }
    6
}

const fn autocorrelation_const(bits: &[u32; CODE_WORDS], shift: usize) -> i32 {
    let mut sum = 0i32;
    let mut k = 0;
    while k < CA_CODE_LENGTH {
        let mut j = k + shift;
        if j >= CA_CODE_LENGTH {
            j -= CA_CODE_LENGTH;
        }
        let a = (bits[k / 32] >> (k % 32)) & 1;
        let b = (bits[j / 32] >> (j % 32)) & 1;
        sum += if a == b { 1 } else { -1 };
        k += 1;
    }
    sum
}

const fn quiet_all() -> [u16; PRN_COUNT] {
    let mut out = [0u16; PRN_COUNT];
    let mut p = 0;
    while p < PRN_COUNT {
        out[p] = quiet_offset_chips(p as u8 + 1);
        p += 1;
    }
    out
}

/// [`quiet_offset_chips`] of every PRN, index `prn − 1`; computed at compile time.
pub static QUIET_OFFSET_CHIPS: [u16; PRN_COUNT] = quiet_all();
