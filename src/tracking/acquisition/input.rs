//! The samples a search reads: the reference antenna's, as decoded `i8` slices or as the bit
//! planes of a 1- or 2-bit front end (a fourth to a sixteenth of the memory: a microcontroller
//! keeps the search's milliseconds packed).

use core::num::NonZeroU32;
use core::ops::Range;

use super::AcquisitionError;
use crate::signal::bitwise::planes::{tail_mask, AntennaPlanes, WORD_SAMPLES};

/// The reference antenna's samples a search reads, from the first one searched.
///
/// Both forms give the search the same values: the planes' `±1`, `±3` are what
/// [`SampleFormat::decode`](crate::signal::SampleFormat::decode) gives for the packed
/// formats, so a search on the planes of a block equals the search on its decoded `i8`
/// samples (tests check it).
#[derive(Clone, Copy, Debug)]
pub enum SearchSamples<'a> {
    /// Decoded samples: in-phase `i`, quadrature `q` (`None` for real samples; at least as
    /// long as `i`). Made by [`SearchSamples::decoded`], which checks that.
    #[non_exhaustive]
    Decoded {
        /// In-phase samples.
        i: &'a [i8],
        /// Quadrature samples (complex baseband), `None` for real samples.
        q: Option<&'a [i8]>,
    },
    /// Bit planes of a 1- or 2-bit front end.
    Planes(AntennaPlanes<'a>),
}

impl<'a> SearchSamples<'a> {
    /// Decoded samples `i` (and `q` for complex ones).
    ///
    /// # Errors
    /// [`AcquisitionError::LengthMismatch`] when `q` is shorter than `i`.
    pub fn decoded(i: &'a [i8], q: Option<&'a [i8]>) -> Result<Self, AcquisitionError> {
        match q {
            Some(q) if q.len() < i.len() => Err(AcquisitionError::LengthMismatch),
            _ => Ok(Self::Decoded { i, q }),
        }
    }

    /// Samples per component.
    pub fn len(&self) -> usize {
        match self {
            Self::Decoded { i, .. } => i.len(),
            Self::Planes(p) => p.len(),
        }
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the samples are complex (in-phase and quadrature).
    pub fn is_complex(&self) -> bool {
        match self {
            Self::Decoded { q, .. } => q.is_some(),
            Self::Planes(p) => p.format().complex,
        }
    }

    /// Calls `f(I − dc[0], Q − dc[1])` for the samples of `range` in order (`Q = 0` and
    /// `dc[1]` unused for real samples; the indices past the end are skipped): the samples
    /// less the search's mean, as the search mixes them. Bounded by the range.
    #[inline]
    pub(super) fn for_each_centred(
        &self,
        range: Range<usize>,
        dc: [f32; 2],
        f: impl FnMut(f32, f32),
    ) {
        let range = range.start..range.end.min(self.len());
        match self {
            Self::Decoded { i, q } => {
                let xs = i.get(range.clone()).unwrap_or_default();
                for_each_decoded(xs, q.map(|q| q.get(range).unwrap_or_default()), dc, f);
            }
            Self::Planes(p) => for_each_planes(p, range, dc, f),
        }
    }

    /// Calls `f(n, ΣI, ΣQ)` for the runs of samples of `range` that share a bin of `clock`
    /// (a run is cut at the range's end), in order: the sums, less `dc` per sample as in
    /// [`Self::for_each_centred`], added sample after sample from 0 (both forms give the same
    /// sums, bit for bit). On planes whose runs hold at most three samples (2.6 Msps
    /// into 1024 bins a millisecond), a run's sums are one table lookup per component.
    /// Bounded by the range.
    #[inline]
    pub(super) fn for_each_bin_sum(
        &self,
        range: Range<usize>,
        dc: [f32; 2],
        clock: BinClock,
        mut f: impl FnMut(u32, f32, f32),
    ) {
        let range = range.start..range.end.min(self.len());
        if let (Self::Planes(p), Some(step)) = (self, clock.short_run_step()) {
            return for_each_short_run(p, range, dc, clock.acc as u32, step, f);
        }
        let (mut acc, mut bin) = (clock.acc, clock.acc >> 32);
        let (mut n, mut sx, mut sy) = (0u32, 0.0f32, 0.0f32);
        self.for_each_centred(range, dc, |x, y| {
            if acc >> 32 != bin {
                f(n, sx, sy);
                (n, sx, sy, bin) = (0, 0.0, 0.0, acc >> 32);
            }
            (n, sx, sy) = (n.wrapping_add(1), sx + x, sy + y);
            acc = acc.wrapping_add(clock.step);
        });
        if n > 0 {
            f(n, sx, sy);
        }
    }

    /// The mean of the first `n` samples (fewer if there are fewer), `[I, Q]` (`Q` 0 for
    /// real samples).
    pub(super) fn mean(&self, n: usize) -> [f32; 2] {
        let n = n.min(self.len());
        if n == 0 {
            return [0.0; 2];
        }
        let [si, sq] = match self {
            Self::Decoded { i, q } => {
                // (a slice in memory sums far inside i64: the saturation never acts)
                let sum = |s: &[i8]| {
                    s.iter()
                        .take(n)
                        .fold(0i64, |a, &x| a.saturating_add(i64::from(x)))
                };
                [sum(i), q.map_or(0, sum)]
            }
            Self::Planes(p) => [
                plane_sum(p.sign_i(), p.mag_i(), n),
                plane_sum(p.sign_q(), p.mag_q(), n),
            ],
        };
        let n = n as f64;
        [(si as f64 / n) as f32, (sq as f64 / n) as f32]
    }
}

/// The bin of each sample of a millisecond's integrate-and-dump: sample `k` of a range
/// falls in bin `(acc + k · step) >> 32` (32.32 fixed point).
#[derive(Clone, Copy, Debug)]
pub(super) struct BinClock {
    /// The bin of the range's first sample, 32.32 fixed point.
    pub acc: u64,
    /// Bins per sample, 32.32 fixed point.
    pub step: u64,
}

impl BinClock {
    /// The step as a fraction of a bin when no run holds more than [`MAX_SHORT_RUN`]
    /// samples (nor less than one).
    fn short_run_step(self) -> Option<NonZeroU32> {
        let step = NonZeroU32::new(u32::try_from(self.step).ok()?)?;
        // the longest run: ⌈2³² / step⌉
        (u32::MAX / step < MAX_SHORT_RUN).then_some(step)
    }
}

/// Most samples of a run that [`for_each_short_run`] sums by a table lookup.
const MAX_SHORT_RUN: u32 = 3;

/// Entries of [`RunSums`]: `4ⁿ` for each run length `n` = 1 … [`MAX_SHORT_RUN`].
const RUN_SUM_ENTRIES: usize = 4 + 16 + 64;

/// The sums of every run of up to [`MAX_SHORT_RUN`] samples of one component, by its
/// length `n` and its sign and magnitude bits `s | m << n` (sample `j` in bit `j`).
struct RunSums([f32; RUN_SUM_ENTRIES]);

impl RunSums {
    /// The sums of the centred `levels` (by `sign << 1 | magnitude`), added sample after
    /// sample from 0 as [`SearchSamples::for_each_bin_sum`] adds them.
    fn new(levels: [f32; 4]) -> Self {
        let mut sums = [0.0; RUN_SUM_ENTRIES];
        let mut at = 0usize;
        for n in 1..=MAX_SHORT_RUN {
            let entries = 1usize.wrapping_shl(n.wrapping_mul(2));
            for (index, sum) in (0..entries).zip(sums.iter_mut().skip(at)) {
                let (s, m) = (
                    index & (1usize.wrapping_shl(n).wrapping_sub(1)),
                    index.wrapping_shr(n),
                );
                *sum = (0..n).fold(0.0f32, |a, j| {
                    let bit = |x: usize| x.wrapping_shr(j) & 1;
                    a + levels[(bit(s) << 1 | bit(m)) & 3]
                });
            }
            at = at.saturating_add(entries);
        }
        Self(sums)
    }

    /// The sum of a run of `n` samples with sign bits `s` and magnitude bits `m`.
    #[inline(always)]
    fn get(&self, n: u32, s: u32, m: u32) -> f32 {
        // the table of length n starts after those of the shorter lengths: (4ⁿ − 4) / 3
        const START: [u32; 4] = [0, 0, 4, 20];
        let index = START[(n & 3) as usize].wrapping_add(s | m.wrapping_shl(n));
        self.0.get(index as usize).copied().unwrap_or(0.0)
    }
}

/// [`SearchSamples::for_each_bin_sum`] on planes whose runs hold at most
/// [`MAX_SHORT_RUN`] samples: each run's length from the clock's fraction `frac` of a bin
/// (`step` per sample), its bits taken from the four planes' current words at once, its sums
/// looked up.
fn for_each_short_run(
    p: &AntennaPlanes<'_>,
    range: Range<usize>,
    dc: [f32; 2],
    mut frac: u32,
    step: NonZeroU32,
    mut f: impl FnMut(u32, f32, f32),
) {
    let sums_i = RunSums::new(centred_levels(dc[0]));
    let sums_q = RunSums::new(if p.format().complex {
        centred_levels(dc[1])
    } else {
        [0.0; 4]
    });
    let planes = [p.sign_i(), p.mag_i(), p.sign_q(), p.mag_q()];
    let words = |w: usize| planes.map(|plane| plane.get(w).copied().unwrap_or(0));
    let mut w = range.start / WORD_SAMPLES;
    let first_bit = (range.start % WORD_SAMPLES) as u32;
    // the current words' samples not yet taken, from bit 0, and how many are left
    let mut current = words(w).map(|x| x.wrapping_shr(first_bit));
    let mut left = (WORD_SAMPLES as u32).wrapping_sub(first_bit);
    let mut k = range.start;
    // (each pass takes at least one sample; the shifts stay below 32 and the differences
    // non-negative: the wrapping forms only keep overflow checks out)
    while k < range.end {
        // the samples left in this bin: ⌈(2³² − frac) / step⌉, at most MAX_SHORT_RUN
        let whole = ((u32::MAX - frac) / step).saturating_add(1);
        let n = whole
            .min(MAX_SHORT_RUN)
            .min(u32::try_from(range.end.wrapping_sub(k)).unwrap_or(MAX_SHORT_RUN));
        let mask = 1u32.wrapping_shl(n).wrapping_sub(1);
        let bits = if n <= left {
            let bits = current.map(|x| x & mask);
            current = current.map(|x| x.wrapping_shr(n));
            left = left.wrapping_sub(n);
            bits
        } else {
            // the run ends in the next words: `left` (< n ≤ 3) samples here, the rest there
            w = w.saturating_add(1);
            let next = words(w);
            let bits: [u32; 4] =
                core::array::from_fn(|i| (current[i] | next[i].wrapping_shl(left)) & mask);
            let taken = n.saturating_sub(left);
            current = next.map(|x| x.wrapping_shr(taken));
            left = (WORD_SAMPLES as u32).saturating_sub(taken);
            bits
        };
        let [si, mi, sq, mq] = bits;
        f(n, sums_i.get(n, si, mi), sums_q.get(n, sq, mq));
        frac = frac.wrapping_add(step.get().wrapping_mul(n));
        k = k.saturating_add(n as usize);
    }
}

/// The centred values of a sample by `sign << 1 | magnitude`, less the mean `dc`: `±1`,
/// `±3` (a missing magnitude plane reads 0: magnitude 1, the 1-bit value).
fn centred_levels(dc: f32) -> [f32; 4] {
    [1.0 - dc, 3.0 - dc, -1.0 - dc, -3.0 - dc]
}

/// The sum of the first `n` values of a sign plane and its magnitude plane (empty for
/// 1-bit; an empty sign plane sums to 0) by population counts, a word at a time:
/// `Σ (1 + 2m)(1 − 2s) = n − 2·#s + 2·#m − 4·#(m ∧ s)`.
fn plane_sum(signs: &[u32], mags: &[u32], n: usize) -> i64 {
    if signs.is_empty() {
        return 0;
    }
    let words = n.div_ceil(WORD_SAMPLES);
    let (mut s, mut m, mut ms) = (0i64, 0i64, 0i64);
    for (w, &sw) in signs.iter().enumerate().take(words) {
        let mask = tail_mask(n, w);
        let (sw, mw) = (sw & mask, mags.get(w).copied().unwrap_or(0) & mask);
        s = s.saturating_add(i64::from(sw.count_ones()));
        m = m.saturating_add(i64::from(mw.count_ones()));
        ms = ms.saturating_add(i64::from((sw & mw).count_ones()));
    }
    // (counts of bits in memory: the saturation never acts)
    let n = i64::try_from(n).unwrap_or(i64::MAX);
    n.saturating_sub(s.saturating_mul(2))
        .saturating_add(m.saturating_mul(2))
        .saturating_sub(ms.saturating_mul(4))
}

/// [`SearchSamples::for_each_centred`] on decoded slices (`ys` no shorter than `xs`).
#[inline(always)]
fn for_each_decoded(xs: &[i8], ys: Option<&[i8]>, dc: [f32; 2], mut f: impl FnMut(f32, f32)) {
    match ys {
        Some(ys) => xs
            .iter()
            .zip(ys)
            .for_each(|(&x, &y)| f(f32::from(x) - dc[0], f32::from(y) - dc[1])),
        None => xs.iter().for_each(|&x| f(f32::from(x) - dc[0], 0.0)),
    }
}

/// [`SearchSamples::for_each_centred`] on bit planes: a word of each plane per 32 samples,
/// each sample's centred value looked up by its sign and magnitude bits.
#[inline(always)]
fn for_each_planes(
    p: &AntennaPlanes<'_>,
    range: Range<usize>,
    dc: [f32; 2],
    mut f: impl FnMut(f32, f32),
) {
    let word = |plane: &[u32], w: usize| plane.get(w).copied().unwrap_or(0);
    // by (sign << 1 | magnitude); a missing magnitude plane reads 0: magnitude 1, the 1-bit
    // value; real planes' Q reads as 0
    let levels_i = centred_levels(dc[0]);
    let levels_q = if p.format().complex {
        centred_levels(dc[1])
    } else {
        [0.0; 4]
    };
    let mut k = range.start;
    while k < range.end {
        let w = k / WORD_SAMPLES;
        let stop = range
            .end
            .min(w.saturating_add(1).saturating_mul(WORD_SAMPLES));
        let b = (k % WORD_SAMPLES) as u32;
        // the word's planes shifted to the first sample; one bit a sample from there
        let (mut si, mut mi) = (word(p.sign_i(), w) >> b, word(p.mag_i(), w) >> b);
        let (mut sq, mut mq) = (word(p.sign_q(), w) >> b, word(p.mag_q(), w) >> b);
        for _ in k..stop {
            let x = levels_i[((si & 1) << 1 | (mi & 1)) as usize];
            let y = levels_q[((sq & 1) << 1 | (mq & 1)) as usize];
            f(x, y);
            (si, mi, sq, mq) = (si >> 1, mi >> 1, sq >> 1, mq >> 1);
        }
        k = stop;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::bitwise::planes::{PlaneBuffer, PlaneFormat, Resolution};

    /// Pseudo-random `±1, ±3` samples.
    fn levels(n: usize, seed: u32) -> [i8; 200] {
        let mut out = [0i8; 200];
        let mut s = seed;
        for x in out.iter_mut().take(n) {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            *x = [1, 3, -1, -3][(s >> 30) as usize];
        }
        out
    }

    /// Pseudo-random samples packed into planes of every format: `check(format, planes,
    /// i, q)` with the values the planes hold (`±1` for 1-bit, `±1, ±3` for 2-bit).
    fn for_each_format(
        seed: u32,
        mut check: impl FnMut(PlaneFormat, &PlaneBuffer<7>, &[i8; 200], &[i8; 200]),
    ) {
        let (i, q) = (levels(200, seed), levels(200, seed + 1));
        for resolution in [Resolution::OneBit, Resolution::TwoBit] {
            for complex in [false, true] {
                let format = PlaneFormat {
                    resolution,
                    complex,
                };
                let mut buffer = PlaneBuffer::<7>::new(format);
                buffer.pack_i8(&i, &q, 2).unwrap();
                let held = |x: i8| match resolution {
                    Resolution::OneBit => x.signum(),
                    Resolution::TwoBit => x,
                };
                check(format, &buffer, &i.map(held), &q.map(held));
            }
        }
    }

    #[test]
    fn planes_read_as_the_decoded_samples_they_pack_over_any_range() {
        for_each_format(1, |format, buffer, i, q| {
            let planes = SearchSamples::Planes(buffer.planes());
            for (start, end) in [(0, 200), (5, 37), (31, 33), (64, 96), (190, 260), (50, 50)] {
                let mut got = [(0f32, 0f32); 200];
                let mut n = 0;
                planes.for_each_centred(start..end, [0.5, -0.25], |x, y| {
                    got[n] = (x, y);
                    n += 1;
                });
                assert_eq!(n, end.min(200).saturating_sub(start));
                for (k, g) in (start..).zip(&got[..n]) {
                    let x = f32::from(i[k]) - 0.5;
                    let y = if format.complex {
                        f32::from(q[k]) + 0.25
                    } else {
                        0.0
                    };
                    assert_eq!(*g, (x, y), "sample {k} of {format:?}");
                }
            }
        });
    }

    /// A millisecond's integrate-and-dump reads the same runs from the planes as from the
    /// decoded samples, bit for bit: on the table path (2.6 Msps into 1024 bins: runs of 2
    /// and 3 samples; exactly 2 samples a bin) and sample by sample (runs of up to 7). Each
    /// run is the samples of one bin of the clock, summed as the samples are.
    #[test]
    fn bin_sums_of_planes_equal_those_of_the_decoded_samples() {
        type Runs = heapless::Vec<(u32, u32, u32), 200>;
        for_each_format(5, |format, buffer, i, q| {
            let decoded = SearchSamples::decoded(i, format.complex.then_some(&q[..])).unwrap();
            let planes = SearchSamples::Planes(buffer.planes());
            let steps = [1_691_556_515u64, 1 << 31, 650_000_000];
            let accs = [0u64, 0x1_8000_0000 + 12_345, 3 << 32 | 0xFFFF_FFFF];
            let ranges = [(0, 200), (5, 37), (29, 95), (31, 33), (190, 260), (50, 50)];
            let clocks = steps
                .iter()
                .flat_map(|&step| accs.map(|acc| BinClock { acc, step }));
            for (clock, (start, end)) in clocks.flat_map(|c| ranges.map(|r| (c, r))) {
                let BinClock { acc, step } = clock;
                let runs = |samples: SearchSamples| {
                    let mut runs = Runs::new();
                    samples.for_each_bin_sum(start..end, [0.5, -0.25], clock, |n, x, y| {
                        runs.push((n, x.to_bits(), y.to_bits())).unwrap();
                    });
                    runs
                };
                let on_planes = runs(planes);
                assert_eq!(on_planes, runs(decoded), "{format:?}, step {step}");
                let bin = |k: usize| (acc + (k - start) as u64 * step) >> 32;
                let mut k = start;
                for &(n, x, _) in &on_planes {
                    let run = k..k + n as usize;
                    assert!(run.clone().all(|j| bin(j) == bin(k)), "{run:?} in one bin");
                    let sum = run.clone().fold(0.0f32, |a, j| a + (f32::from(i[j]) - 0.5));
                    assert_eq!(x, sum.to_bits(), "{run:?}");
                    k = run.end;
                    assert!(
                        k == end.min(200) || bin(k) != bin(k - 1),
                        "a run ends at a bin"
                    );
                }
                assert_eq!(k, end.min(200).max(start));
            }
        });
    }

    #[test]
    fn the_mean_of_planes_equals_the_mean_of_the_decoded_samples() {
        for_each_format(3, |format, buffer, i, q| {
            let decoded = SearchSamples::decoded(i, format.complex.then_some(&q[..])).unwrap();
            for n in [0, 1, 31, 32, 33, 150, 1000] {
                assert_eq!(
                    SearchSamples::Planes(buffer.planes()).mean(n),
                    decoded.mean(n),
                    "{format:?}, {n} samples"
                );
            }
        });
    }

    #[test]
    fn a_quadrature_shorter_than_the_in_phase_is_refused() {
        let x = [1i8; 10];
        assert_eq!(
            SearchSamples::decoded(&x, Some(&x[..9])).unwrap_err(),
            AcquisitionError::LengthMismatch
        );
        assert!(SearchSamples::decoded(&x[..9], Some(&x)).is_ok());
    }
}
