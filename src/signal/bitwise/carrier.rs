//! The carrier replica as words: quantized `cos` and `sin` signs (and zero masks) of 32
//! samples a word, from the exact 32-bit carrier NCO, without a per-sample loop.
//!
//! # The replica this realizes
//! Sample `k` has the NCO phase `φ_k` (2⁻³² cycle, the same accumulator as
//! [`CarrierNco`](crate::signal::nco::CarrierNco)). The replica `r_k = c_k + j s_k`:
//!
//! * **2-level**: the quadrant `φ_k ≫ 30` selects `c = sign cos`, `s = sign sin` of the
//!   quadrant (`c, s ∈ {±1}`): four phases at 45° + n·90°, `|r| = √2`.
//! * **3-level**: the sector `φ_k ≫ 28` (16 sectors) selects `c, s ∈ {−1, 0, +1}`: `c = 0` in
//!   the four sectors around the zeros of `cos` (`|φ − ¼|, |φ − ¾| < 1/16` cycle), else its
//!   sign; `s` likewise around the zeros of `sin`. A quarter of the samples have `c = 0`,
//!   another quarter `s = 0`.
//!
//! Bit planes: `C` (bit set: `c < 0`), `S` (`s < 0`), and for the 3-level replica the non-zero
//! masks `NZc`, `NZs`. All of them are most-significant bits of the phase ramp with a fixed
//! offset: `S₂ = msb(φ)`, `C₂ = msb(φ + ¼)`; `S₃ = msb(φ − 1/16)`, `C₃ = msb(φ + 3/16)`,
//! `Zs = S₃ ⊕ msb(φ + 1/16)`, `Zc = C₃ ⊕ msb(φ + 5/16)`.
//!
//! # How a word is made
//! The step is split `δ = m·2³⁰ + δ_s` with `m ∈ 0..4` and `|δ_s| ≤ 2²⁹` (an eighth of a cycle
//! per sample). Adding `k·m` quarter cycles to the phase adds exactly `k·m mod 4` to its
//! quadrant (the low 30 bits are untouched), so the quadrant planes of the *slow* ramp
//! `ψ_k = φ₀ + k·δ_s` plus the constant pattern `k·m mod 4` (a bit-sliced 2-bit add: four
//! operations) give the planes of `φ`. The most significant bit of the slow ramp toggles at
//! most twice a word when `|δ_s| ≤ 2²⁷` (a word spans at most one cycle: Doppler up to
//! `f_s/32` away from a multiple of `f_s/4`, i.e. ±81 kHz at 2.6 Msps), at most eight times
//! otherwise: the first toggle is `k₁ = ⌈(2³¹ − (ψ₀ mod 2³¹))/δ_s⌉` (one division), the next
//! `k₁ + h` or `k₁ + h + 1` with `h = ⌊2³¹/δ_s⌋` (decided exactly by the remainder), and the
//! plane is the start bit XOR the masks `bits ≥ k` of the toggles. A negative slow step
//! runs the same computation backwards from the word's last sample and reverses the bits.
//! Exact: equal to the per-sample evaluation bit for bit (tests check it).

/// Quantization levels of the carrier replica.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CarrierLevels {
    /// `c, s ∈ {±1}`: four phases; correlation loss 0.91 dB, the cheapest.
    #[default]
    Two,
    /// `c, s ∈ {−1, 0, +1}` with a quarter zeros each: loss 0.35 dB; costs a mask per
    /// popcount (real samples) or twice the popcounts (complex samples).
    Three,
}

/// The carrier words of one word of samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct CarrierWords {
    /// Bit set: `c < 0`.
    pub(crate) c: u32,
    /// Bit set: `s < 0`.
    pub(crate) s: u32,
    /// `C ⊕ S` (the quadrant's low bit; 2-level only).
    pub(crate) d: u32,
    /// Samples counted by the `c` sums: `c ≠ 0` (3-level) and inside the span.
    pub(crate) nzc: u32,
    /// Samples counted by the `s` sums: `s ≠ 0` (3-level) and inside the span.
    pub(crate) nzs: u32,
}

/// Largest slow step of the two-toggle path (a word spans at most one cycle).
const FAST_SLOW_STEP: u32 = 1 << 27;

/// Half a cycle, 2⁻³² cycle.
const HALF: u32 = 1 << 31;

/// The carrier step prepared for word generation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CarrierStep {
    /// The slow part, 2⁻³² cycle per sample, `|δ_s| ≤ 2²⁹`.
    slow: i32,
    /// `|δ_s|`.
    mag: u32,
    /// `⌊2³¹/|δ_s|⌋` (0 for a zero slow step).
    h: u32,
    /// `2³¹ − h·|δ_s|`.
    rem: u32,
    /// Pattern `k·m mod 4`, low bit plane.
    p0: u32,
    /// Pattern `k·m mod 4`, high bit plane.
    p1: u32,
}

impl CarrierStep {
    /// Splits the NCO step `δ` (2⁻³² cycle per sample, two's complement).
    pub(crate) fn new(step: u32) -> Self {
        let m = (step.wrapping_add(1 << 29) >> 30) & 3;
        let slow = step.wrapping_sub(m << 30) as i32;
        let mag = slow.unsigned_abs();
        let (h, rem) = match HALF.checked_div(mag) {
            Some(h) => (h, HALF - h * mag),
            None => (0, 0),
        };
        let (p0, p1) = match m {
            1 => (0xaaaa_aaaa, 0xcccc_cccc),
            2 => (0, 0xaaaa_aaaa),
            3 => (0xaaaa_aaaa, 0x6666_6666),
            _ => (0, 0),
        };
        Self {
            slow,
            mag,
            h,
            rem,
            p0,
            p1,
        }
    }

    /// Whether the two-toggle path applies.
    pub(crate) fn fast(&self) -> bool {
        self.mag <= FAST_SLOW_STEP
    }

    /// The slow ramp's advance over one word.
    fn word_advance(&self) -> u32 {
        (self.slow as u32).wrapping_mul(32)
    }
}

/// Bits `k … 31` (none for `k ≥ 32`).
#[inline(always)]
fn above(k: u32) -> u32 {
    if k < 32 {
        u32::MAX << k
    } else {
        0
    }
}

/// The start bit of the ramp at `psi`, all ones when the most significant bit is set.
#[inline(always)]
fn start(psi: u32) -> u32 {
    ((psi as i32) >> 31) as u32
}

/// Most significant bits of `psi + k·d`, `k = 0..31`, for `0 < d ≤ 2²⁷` (at most two toggles).
#[inline(always)]
fn msb_up_fast(psi: u32, st: &CarrierStep) -> u32 {
    let d = st.mag;
    let r = psi & (HALF - 1);
    let k1 = ((HALF - 1 - r) / d.max(1)).saturating_add(1).min(32);
    // Position past the boundary at the first toggle, in [0, d) when k1 < 32.
    let e1 = r.wrapping_add(k1.wrapping_mul(d)).wrapping_sub(HALF);
    let k2 = k1 + st.h.min(32) + u32::from(e1 < st.rem);
    start(psi) ^ above(k1) ^ above(k2)
}

/// Most significant bits of `psi + k·d`, `k = 0..31`, for `0 < d ≤ 2²⁹` (at most eight
/// toggles, a bounded loop).
#[inline(always)]
fn msb_up_general(psi: u32, st: &CarrierStep) -> u32 {
    let d = st.mag;
    let r = psi & (HALF - 1);
    let mut k = ((HALF - 1 - r) / d.max(1)).saturating_add(1).min(32);
    let mut e = r.wrapping_add(k.wrapping_mul(d)).wrapping_sub(HALF);
    let mut mask = 0u32;
    // Bounded: toggles are at least 4 samples apart (d ≤ 2²⁹), so at most 8 fall in 1..31.
    for _ in 0..8 {
        if k >= 32 {
            break;
        }
        mask ^= above(k);
        let gap = st.h + u32::from(e < st.rem);
        e = e.wrapping_add(gap.wrapping_mul(d)).wrapping_sub(HALF);
        k += gap;
    }
    start(psi) ^ mask
}

/// Most significant bits of `psi + k·δ_s`, `k = 0..31`.
#[inline(always)]
fn msb_plane<const FAST: bool>(psi: u32, st: &CarrierStep) -> u32 {
    let up = |p: u32| {
        if FAST {
            msb_up_fast(p, st)
        } else {
            msb_up_general(p, st)
        }
    };
    if st.slow > 0 {
        up(psi)
    } else if st.slow < 0 {
        // Backwards from the last sample: psi + 31·δ_s + j·|δ_s| is sample 31 − j.
        up(psi.wrapping_add((st.slow as u32).wrapping_mul(31))).reverse_bits()
    } else {
        start(psi)
    }
}

/// Quadrant planes `(q1, q0)` of `φ_k = psi + k·δ` from the most significant bits of the slow
/// ramp at `psi` (`a`) and at `psi + ¼` (`b`): `q1 = a`, `q0 = a ⊕ b`, plus `k·m mod 4`.
#[inline(always)]
fn rotate(a: u32, b: u32, st: &CarrierStep) -> (u32, u32) {
    let q0 = a ^ b;
    let q1 = a ^ st.p1 ^ (q0 & st.p0);
    (q1, q0 ^ st.p0)
}

/// Fills `out` with the 2-level carrier words of consecutive words, the first starting at
/// phase `phase`; returns the phase after them. Masks are all ones.
pub(crate) fn two_level(out: &mut [CarrierWords], phase: u32, st: &CarrierStep) -> u32 {
    if st.fast() {
        two_level_with::<true>(out, phase, st)
    } else {
        two_level_with::<false>(out, phase, st)
    }
}

#[inline(always)]
fn two_level_with<const FAST: bool>(
    out: &mut [CarrierWords],
    mut psi: u32,
    st: &CarrierStep,
) -> u32 {
    let adv = st.word_advance();
    for w in out.iter_mut() {
        let a = msb_plane::<FAST>(psi, st);
        let b = msb_plane::<FAST>(psi.wrapping_add(1 << 30), st);
        let (q1, q0) = rotate(a, b, st);
        *w = CarrierWords {
            c: q1 ^ q0,
            s: q1,
            d: q0,
            nzc: u32::MAX,
            nzs: u32::MAX,
        };
        psi = psi.wrapping_add(adv);
    }
    psi
}

/// Fills `out` with the 3-level carrier words (see the module documentation); returns the
/// phase after them.
pub(crate) fn three_level(out: &mut [CarrierWords], phase: u32, st: &CarrierStep) -> u32 {
    if st.fast() {
        three_level_with::<true>(out, phase, st)
    } else {
        three_level_with::<false>(out, phase, st)
    }
}

#[inline(always)]
fn three_level_with<const FAST: bool>(
    out: &mut [CarrierWords],
    mut psi: u32,
    st: &CarrierStep,
) -> u32 {
    const SIXTEENTH: u32 = 1 << 28;
    let adv = st.word_advance();
    for w in out.iter_mut() {
        // msb(φ − 1/16) and msb(φ + 3/16): the quadrant of φ − 1/16.
        let a = msb_plane::<FAST>(psi.wrapping_sub(SIXTEENTH), st);
        let b = msb_plane::<FAST>(psi.wrapping_add(3 * SIXTEENTH), st);
        // msb(φ + 1/16) and msb(φ + 5/16): the quadrant of φ + 1/16.
        let e = msb_plane::<FAST>(psi.wrapping_add(SIXTEENTH), st);
        let f = msb_plane::<FAST>(psi.wrapping_add(5 * SIXTEENTH), st);
        let (q1, q0) = rotate(a, b, st);
        let (r1, r0) = rotate(e, f, st);
        let s = q1;
        let c = q1 ^ q0;
        *w = CarrierWords {
            c,
            s,
            d: c ^ s,
            nzc: !(c ^ r1 ^ r0),
            nzs: !(s ^ r1),
        };
        psi = psi.wrapping_add(adv);
    }
    psi
}

/// The 2-level replica of phase `phase`: `(c, s)`, each ±1 (per-sample definition).
pub fn two_level_replica(phase: u32) -> (i8, i8) {
    match phase >> 30 {
        0 => (1, 1),
        1 => (-1, 1),
        2 => (-1, -1),
        _ => (1, -1),
    }
}

/// The 3-level replica of phase `phase`: `(c, s)`, each in {−1, 0, 1} (per-sample
/// definition: sector `phase ≫ 28`).
pub fn three_level_replica(phase: u32) -> (i8, i8) {
    const C: [i8; 16] = [1, 1, 1, 0, 0, -1, -1, -1, -1, -1, -1, 0, 0, 1, 1, 1];
    const S: [i8; 16] = [0, 1, 1, 1, 1, 1, 1, 0, 0, -1, -1, -1, -1, -1, -1, 0];
    let k = (phase >> 28) as usize & 15;
    (C[k], S[k])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(step: u32, phase: u32, words: usize) {
        let st = CarrierStep::new(step);
        let mut two = [CarrierWords::default(); 8];
        let mut three = [CarrierWords::default(); 8];
        let end2 = two_level(&mut two[..words], phase, &st);
        let end3 = three_level(&mut three[..words], phase, &st);
        assert_eq!(
            end2,
            phase.wrapping_add(step.wrapping_mul(32 * words as u32))
        );
        assert_eq!(end3, end2);
        for w in 0..words {
            for k in 0..32 {
                let ph = phase.wrapping_add(step.wrapping_mul((32 * w + k) as u32));
                let bit = |x: u32| (x >> k) & 1;
                let (c, s) = two_level_replica(ph);
                let ctx = (step, ph, w, k);
                assert_eq!(bit(two[w].c), u32::from(c < 0), "2c {ctx:?}");
                assert_eq!(bit(two[w].s), u32::from(s < 0), "2s {ctx:?}");
                assert_eq!(bit(two[w].d), u32::from((c < 0) != (s < 0)), "2d {ctx:?}");
                let (c, s) = three_level_replica(ph);
                assert_eq!(bit(three[w].nzc), u32::from(c != 0), "3nzc {ctx:?}");
                assert_eq!(bit(three[w].nzs), u32::from(s != 0), "3nzs {ctx:?}");
                if c != 0 {
                    assert_eq!(bit(three[w].c), u32::from(c < 0), "3c {ctx:?}");
                }
                if s != 0 {
                    assert_eq!(bit(three[w].s), u32::from(s < 0), "3s {ctx:?}");
                }
            }
        }
    }

    #[test]
    fn words_equal_the_per_sample_replica() {
        let mut x = 0x1234_5678u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        // Edge steps: zero, ±1, the fast/general boundary, the largest slow steps, and the
        // exact multiples of a quarter cycle (IF = f_s/4, f_s/2).
        let edges = [
            0u32,
            1,
            u32::MAX,
            1 << 27,
            (1 << 27) + 1,
            (1u32 << 27).wrapping_neg(),
            (1 << 29) - 1,
            (1u32 << 29).wrapping_neg(),
            1 << 30,
            (1 << 30) + 12345,
            2 << 30,
            3 << 30,
            (3u32 << 30).wrapping_sub(777),
        ];
        for &step in &edges {
            for _ in 0..20 {
                check(step, next(), 4);
            }
            check(step, 0, 3);
            check(step, u32::MAX, 3);
            check(step, 1 << 31, 3);
        }
        for _ in 0..3000 {
            let step = next();
            let small = (next() as i32 >> (next() % 30)) as u32;
            check(step, next(), 2);
            check(small, next(), 2);
        }
    }
}
