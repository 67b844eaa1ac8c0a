//! The samples a search reads: the reference antenna's, as decoded `i8` slices or as the bit
//! planes of a 1- or 2-bit front end (a fourth to a sixteenth of the memory: a microcontroller
//! keeps the search's milliseconds packed).

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
    let centred = |dc: f32| [1.0 - dc, 3.0 - dc, -1.0 - dc, -3.0 - dc];
    let levels_i = centred(dc[0]);
    let levels_q = if p.format().complex {
        centred(dc[1])
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
