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
//! masks `NZc`, `NZs`. They are functions of a small phase index: the quadrant `Q = φ ≫ 30`
//! (2-level: `S = q₁`, `C = q₁ ⊕ q₀`) or the octant `O` of `φ + 1/16` (3-level: octant `o`
//! holds sectors `2o − 1` and `2o`, so `NZc = ¬o₁ ∨ o₀`, `NZs = o₁ ∨ o₀`, `C = o₂ ⊕ (o₁ ∧ o₀)`,
//! `S = o₂`).
//!
//! # How a word is made
//! The step is split `δ = m·2³⁰ + δ_s` with `m ∈ 0..4` and `|δ_s| ≤ 2²⁹` (an eighth of a cycle
//! per sample). Adding `k·m` quarter cycles to the phase adds exactly `k·m mod 4` quarters to
//! its index (the lower bits are untouched), so the index planes of the *slow* ramp
//! `ψ_k = φ₀ + k·δ_s`, plus the constant pattern `k·m mod 4` in the quarter bits (a
//! bit-sliced 2-bit add: four operations), give the planes of `φ`. The slow ramp's index
//! changes by one at each crossing of an index boundary; in a word there are at most
//! `T = 1 + ⌊30/h⌋` of them, `h = ⌊U/|δ_s|⌋`, `U` the index unit (2³⁰ or 2²⁹): one for a
//! carrier within `f_s/124` of a multiple of `f_s/4` (±21 kHz at 2.6 Msps, 2-level; half that
//! for the 3-level octants), two within `f_s/60` (±43 kHz). The first crossing is `k₁ = ⌈(U − (ψ₀ mod U))/δ_s⌉` (one division), each next one
//! `h` or `h + 1` later (decided exactly by the remainder), and the index planes are the start
//! index's bits XOR the masks `bits ≥ k_j` of the crossings that flip them. A negative slow
//! step runs the same computation backwards from the word's last sample and reverses the bits.
//! `T` is a compile-time constant per span (1, 2, 4, 8 or 32), so the word loop has no
//! data-dependent branch. When crossings are at least a word apart (`h ≥ 32`: within `f_s/128`
//! of a multiple of `f_s/4` for the 2-level replica) the next crossing and its remainder are
//! carried from word to word instead (no division per word), and a falling ramp is the
//! complement of the rising `¬ψ_k = ¬ψ₀ + k·|δ_s|`. Exact: equal to the per-sample evaluation
//! bit for bit (tests check it).

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
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
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

/// The carrier step prepared for word generation.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct CarrierStep {
    /// The slow part, 2⁻³² cycle per sample, `|δ_s| ≤ 2²⁹`.
    slow: i32,
    /// `|δ_s|`.
    mag: u32,
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
        let (p0, p1) = match m {
            1 => (0xaaaa_aaaa, 0xcccc_cccc),
            2 => (0, 0xaaaa_aaaa),
            3 => (0xaaaa_aaaa, 0x6666_6666),
            _ => (0, 0),
        };
        Self {
            slow,
            mag: slow.unsigned_abs(),
            p0,
            p1,
        }
    }

    /// The slow ramp's advance over one word.
    fn word_advance(&self) -> u32 {
        (self.slow as u32).wrapping_mul(32)
    }
}

/// The crossings of index boundaries (every `2^(32 − B)`) by an increasing ramp.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Crossings {
    /// `|δ_s|`, at least 1.
    d: u32,
    /// `⌊U/d⌋`, at most 64.
    h: u32,
    /// `U − ⌊U/d⌋·d`.
    rem: u32,
}

impl Crossings {
    fn new(d: u32, bits: u32) -> Self {
        let unit = 1u32 << (32 - bits);
        let d = d.max(1);
        let h = unit / d;
        Self {
            d,
            h: h.min(64),
            rem: unit % d, // (= unit − h·d)
        }
    }

    /// Crossings in positions 1–31 of a word at most (`1 + ⌊30/h⌋`).
    fn per_word(&self) -> u32 {
        1 + 30 / self.h.max(1)
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

/// All ones when bit `b` of `x` is set.
#[inline(always)]
fn spread(x: u32, b: u32) -> u32 {
    0u32.wrapping_sub((x >> b) & 1)
}

/// Planes of the top `B` bits (the index) of `psi + k·d`, `k = 0..31`, for an increasing ramp
/// (`c.d > 0`), with at most `T` crossings in the word (the caller's bound).
#[inline(always)]
fn index_up<const B: u32, const T: usize>(psi: u32, c: &Crossings) -> [u32; 3] {
    let unit = 1u32 << (32 - B);
    let start = psi >> (32 - B);
    let r = psi & (unit - 1);
    let mut k = ((unit - 1 - r) / c.d).saturating_add(1).min(32);
    // Position past the boundary at the crossing, in [0, d) while k < 32.
    let mut e = r.wrapping_add(k.wrapping_mul(c.d)).wrapping_sub(unit);
    let mut planes = [spread(start, 0), spread(start, 1), spread(start, 2)];
    for j in 0..T as u32 {
        let mask = above(k);
        // The index goes from start + j to start + j + 1: the bits that change flip.
        let x = start.wrapping_add(j);
        let flips = x ^ x.wrapping_add(1);
        planes[0] ^= mask;
        planes[1] ^= mask & spread(flips, 1);
        if B > 2 {
            planes[2] ^= mask & spread(flips, 2);
        }
        let bump = u32::from(e < c.rem);
        e = e.wrapping_sub(c.rem).wrapping_add(bump.wrapping_mul(c.d));
        // (k ≥ 32 masks nothing: saturating keeps that, and the sum's bound visible)
        k = k.saturating_add(c.h).saturating_add(bump);
    }
    planes
}

/// Planes of the index of `psi + k·δ_s`, `k = 0..31`.
#[inline(always)]
fn index_planes<const B: u32, const T: usize>(
    psi: u32,
    st: &CarrierStep,
    c: &Crossings,
) -> [u32; 3] {
    if st.slow > 0 {
        index_up::<B, T>(psi, c)
    } else if st.slow < 0 {
        // Backwards from the last sample: psi + 31·δ_s + j·|δ_s| is sample 31 − j.
        let start = psi.wrapping_add((st.slow as u32).wrapping_mul(31));
        index_up::<B, T>(start, c).map(u32::reverse_bits)
    } else {
        let i = psi >> (32 - B);
        [spread(i, 0), spread(i, 1), spread(i, 2)]
    }
}

/// Adds the pattern `k·m mod 4` to the quarter bits `(hi, lo)` of an index (bit-sliced).
#[inline(always)]
fn rotate(hi: u32, lo: u32, st: &CarrierStep) -> (u32, u32) {
    (hi ^ st.p1 ^ (lo & st.p0), lo ^ st.p0)
}

/// Fills `out` with the carrier words of consecutive words, the first starting at phase
/// `phase`. 2-level masks are all ones.
#[inline(always)]
pub(crate) fn fill(out: &mut [CarrierWords], levels: CarrierLevels, phase: u32, st: &CarrierStep) {
    match levels {
        CarrierLevels::Two => fill_levels::<false>(out, phase, st),
        CarrierLevels::Three => fill_levels::<true>(out, phase, st),
    }
}

#[inline(always)]
fn fill_levels<const L3: bool>(out: &mut [CarrierWords], phase: u32, st: &CarrierStep) {
    let bits = if L3 { 3 } else { 2 };
    let c = Crossings::new(st.mag, bits);
    if st.slow != 0 && c.h >= WORD_BITS {
        return fill_sparse::<L3>(out, phase, st, &c);
    }
    match c.per_word() {
        0..=1 => fill_with::<L3, 1>(out, phase, st, &c),
        2 => fill_with::<L3, 2>(out, phase, st, &c),
        3..=4 => fill_with::<L3, 4>(out, phase, st, &c),
        5..=8 => fill_with::<L3, 8>(out, phase, st, &c),
        _ => fill_with::<L3, 32>(out, phase, st, &c),
    }
}

/// The carrier words of the slow ramp's index planes (bit 0 first; the octant of `φ + 1/16`
/// for the 3-level replica, the quadrant of `φ` for the 2-level one, whose third plane is
/// unused), rotated by the step's whole quarter cycles.
#[inline(always)]
fn words_of_index<const L3: bool>(o0: u32, o1: u32, o2: u32, st: &CarrierStep) -> CarrierWords {
    if L3 {
        let (o2, o1) = rotate(o2, o1, st);
        CarrierWords {
            c: o2 ^ (o1 & o0),
            s: o2,
            d: 0,
            nzc: !o1 | o0,
            nzs: o1 | o0,
        }
    } else {
        let (q1, q0) = rotate(o1, o0, st);
        CarrierWords {
            c: q1 ^ q0,
            s: q1,
            d: q0,
            nzc: u32::MAX,
            nzs: u32::MAX,
        }
    }
}

/// Samples per word.
const WORD_BITS: u32 = 32;

/// The slow ramp's index crossings carried from word to word, for slow steps of at least a
/// word between crossings (`h ≥ 32`: at most one per word, the LEO case: within `f_s/128` of a
/// multiple of `f_s/4` for the 2-level replica). Instead of finding each word's first crossing
/// anew (a division per word), the next crossing's sample and its position past the boundary
/// are kept, as [`index_up`] keeps them within a word. A negative slow step ramps `¬ψ` up
/// (`¬ψ_k = ¬ψ₀ + k·|δ_s|` exactly), whose index is the complement of `ψ`'s. Equal to
/// [`fill_with`] bit for bit.
#[inline(always)]
fn fill_sparse<const L3: bool>(
    out: &mut [CarrierWords],
    phase: u32,
    st: &CarrierStep,
    c: &Crossings,
) {
    let bits = if L3 { 3 } else { 2 };
    let unit = 1u32 << (32 - bits);
    let offset = if L3 { 1u32 << 28 } else { 0 };
    let psi = phase.wrapping_add(offset);
    // the index planes are complemented for a falling ramp
    let (psi, invert) = if st.slow > 0 {
        (psi, 0)
    } else {
        (!psi, u32::MAX)
    };
    let r = psi & (unit - 1);
    let mut index = psi >> (32 - bits);
    // Samples from the word's start to the next crossing, and its position past the boundary
    // (in [0, d)), as in `index_up`: k·d ≤ unit − 1 − r + d, no wrap.
    let mut k = (unit - 1 - r) / c.d + 1;
    let mut e = r.wrapping_add(k.wrapping_mul(c.d)).wrapping_sub(unit);
    // Samples between crossings: h or h + 1 (`c.h` is capped at a word's reach).
    let h = unit / c.d;
    for w in out.iter_mut() {
        // the word's index planes: the index, and the next one from the crossing on
        let mask = above(k);
        let flips = index ^ index.wrapping_add(1);
        let plane = |j: u32| spread(index, j) ^ (mask & spread(flips, j)) ^ invert;
        let (o0, o1, o2) = (plane(0), plane(1), plane(2));
        if k < WORD_BITS {
            index = index.wrapping_add(1);
            let bump = u32::from(e < c.rem);
            e = e.wrapping_sub(c.rem).wrapping_add(bump.wrapping_mul(c.d));
            // (k < 32, h ≤ 2³⁰: no wrap)
            k = k.wrapping_add(h).wrapping_add(bump);
        }
        // (k ≥ 32 here: a crossing moved it on by h ≥ 32)
        k = k.wrapping_sub(WORD_BITS);
        *w = words_of_index::<L3>(o0, o1, o2, st);
    }
}

#[inline(always)]
fn fill_with<const L3: bool, const T: usize>(
    out: &mut [CarrierWords],
    phase: u32,
    st: &CarrierStep,
    c: &Crossings,
) {
    let adv = st.word_advance();
    let mut psi = phase;
    for w in out.iter_mut() {
        *w = if L3 {
            // Octant of φ + 1/16.
            let [o0, o1, o2] = index_planes::<3, T>(psi.wrapping_add(1 << 28), st, c);
            words_of_index::<true>(o0, o1, o2, st)
        } else {
            let [q0, q1, _] = index_planes::<2, T>(psi, st, c);
            words_of_index::<false>(q0, q1, 0, st)
        };
        psi = psi.wrapping_add(adv);
    }
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
        let mut two = [CarrierWords::default(); 30];
        let mut three = [CarrierWords::default(); 30];
        fill(&mut two[..words], CarrierLevels::Two, phase, &st);
        fill(&mut three[..words], CarrierLevels::Three, phase, &st);
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
        // Slow steps over a whole chunk: crossings carried from word to word (at and near the
        // boundary of one crossing per word, h = 32, for both index units; a crossing on a
        // word's first sample), rising and falling.
        for base in [1u32 << 25, 1 << 24, 1 << 20, 12_345, 1] {
            for delta in [0u32, 1, 2] {
                for step in [base.saturating_sub(delta).max(1), base + delta] {
                    for _ in 0..20 {
                        check(step, next(), 30);
                        check(step.wrapping_neg(), next(), 30);
                    }
                    check(step, 0u32.wrapping_sub(step.wrapping_mul(32)), 30);
                    check(step.wrapping_neg(), step.wrapping_mul(32), 30);
                }
            }
        }
        for _ in 0..3000 {
            let step = next();
            let small = (next() as i32 >> (next() % 30)) as u32;
            check(step, next(), 2);
            check(small, next(), 2);
            check(small, next(), 30);
        }
    }
}
