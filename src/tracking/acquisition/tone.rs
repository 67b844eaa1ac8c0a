//! Continuous-wave interference: found in the samples' spectrum, its frequency refined from
//! the phase progression of its millisecond phasors, and cancelled sample by sample before
//! the integrate-and-dump (which would otherwise spread a tone into a comb of lines through
//! its uneven sample counts per bin, too many and too weak to excise).
//!
//! For a tone at `ω` (rad/sample, from the IF-mixed spectrum of millisecond 0: the strongest
//! local maxima above [`TONE_FACTOR`] times the background line power, parabola-refined), the
//! phasor of millisecond `m` is `a_m = c · mean_k (x_k e^{−jωk})` (`c` = 1 for complex samples,
//! 2 for real ones, whose tone is `Re(a e^{jωk})`); the frequency error is the mean phase step
//! between consecutive phasors over one millisecond (unambiguous within ±500 Hz,
//! [`REFINE_STEPS`] steps over [`REFINE_MS`] ms), and the cancellation subtracts
//! `a_m e^{jωk}` (its real part for real samples) from every sample of millisecond `m`, the
//! phasor measured again for each millisecond mixed (no storage; one more pass over the
//! millisecond's samples per tone, only when a tone was found).

use super::{Acquisition, AcquisitionConfig, SearchSamples};
use crate::signal::nco::{carrier_index, CarrierNco, CARRIER_AMPLITUDE, COS_TABLE, SIN_TABLE};
use crate::tracking::fft::Complex;

/// Most tones cancelled (a tone clipped by the front end brings its odd harmonics).
pub(super) const MAX_TONES: usize = 8;

/// A spectral line above this many times the background line power is a tone to cancel.
pub const TONE_FACTOR: f32 = 30.0;

/// Milliseconds whose phasors refine a tone's frequency.
const REFINE_MS: usize = 8;

/// Refinement steps of a tone's frequency.
const REFINE_STEPS: usize = 2;

/// One tone to cancel: its frequency in the samples (IF included), carrier NCO step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(super) struct Tone {
    step: u32,
}

impl Tone {
    /// No tone (the engine's empty slots).
    pub(super) const NONE: Self = Self { step: 0 };

    /// The NCO step of the tone.
    pub(super) fn step(&self) -> u32 {
        self.step
    }

    /// The tone's phasor over millisecond `m` (least squares for a pure tone; phase from
    /// sample 0), sample units.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub(super) fn phasor(
        &self,
        m: usize,
        samples: SearchSamples<'_>,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> Complex {
        let gain = if samples.is_complex() { 1.0 } else { 2.0 };
        let dq = if samples.is_complex() { dc[1] } else { 0.0 };
        let (start, end) = (
            config.ms_start(m),
            config.ms_start(m.saturating_add(1)).min(samples.len()),
        );
        let mut phase = self.step.wrapping_mul(start as u32);
        let (mut sr, mut si) = (0.0f32, 0.0f32);
        samples.for_each_centred(start..end, [dc[0], dq], |x, y| {
            let idx = carrier_index(phase);
            let (c, s) = (f32::from(COS_TABLE[idx]), f32::from(SIN_TABLE[idx]));
            // (x + jy) · e^{−jθ}
            sr += x * c + y * s;
            si += y * c - x * s;
            phase = phase.wrapping_add(self.step);
        });
        let n = end.saturating_sub(start).max(1) as f32 * f32::from(CARRIER_AMPLITUDE);
        [gain * sr / n, gain * si / n]
    }
}

/// `a · e^{jθ}` for the carrier-table phase `phase`, `[I, Q]`.
#[inline(always)]
pub(super) fn rotate(a: Complex, phase: u32) -> Complex {
    let idx = carrier_index(phase);
    let scale = 1.0 / f32::from(CARRIER_AMPLITUDE);
    let (c, s) = (
        f32::from(COS_TABLE[idx]) * scale,
        f32::from(SIN_TABLE[idx]) * scale,
    );
    [a[0] * c - a[1] * s, a[0] * s + a[1] * c]
}

impl<const N: usize, const L: usize> Acquisition<N, L> {
    /// Finds up to [`MAX_TONES`] tones in `self.data` (the IF-mixed spectrum of millisecond
    /// 0, background line power `level`) and refines their frequencies. Returns how many.
    pub(super) fn find_tones(
        &mut self,
        samples: SearchSamples<'_>,
        level: f32,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> usize {
        self.tone_count = 0;
        if !(level > 0.0) {
            return 0;
        }
        let mut lines = [(0.0f32, 0.0f32); MAX_TONES]; // (power, frequency Hz)
        let power = |d: &Complex| d[0] * d[0] + d[1] * d[1];
        // Rolling powers of lines k − 1, k, k + 1 (each computed once).
        let (mut before, mut p) = (power(&self.data[N - 1]), power(&self.data[0]));
        for k in 0..N {
            let after = power(&self.data[k.wrapping_add(1) & (N - 1)]);
            if p > TONE_FACTOR * level && p >= before && p > after {
                // Parabola through the amplitudes; bin k is k kHz (wrapped to ±N/2).
                let (a0, am, ap) = (crate::sqrtf(p), crate::sqrtf(before), crate::sqrtf(after));
                let curv = 2.0 * a0 - am - ap;
                let delta = if curv > 0.0 {
                    (0.5 * (ap - am) / curv).clamp(-0.5, 0.5)
                } else {
                    0.0
                };
                let bin = if k < N / 2 {
                    k as f32
                } else {
                    k as f32 - N as f32
                };
                let weakest = lines.iter_mut().min_by(|a, b| a.0.total_cmp(&b.0));
                if let Some(w) = weakest.filter(|w| p > w.0) {
                    *w = (p, 1000.0 * (bin + delta));
                }
            }
            (before, p) = (p, after);
        }
        let ms = 2 * usize::from(config.noncoherent_ms);
        let mut count = 0usize;
        for &(_, f) in lines.iter().filter(|l| l.0 > 0.0) {
            if let Some(slot) = self.tones.get_mut(count) {
                *slot = refine_tone(f, samples, ms, config, dc);
                count = count.saturating_add(1); // (at most the tones' capacity)
            }
        }
        self.tone_count = count;
        count
    }
}

/// The tone near baseband frequency `f_hz`, refined from its phasors' phase steps over the
/// first milliseconds (at most `ms`).
fn refine_tone(
    f_hz: f32,
    samples: SearchSamples<'_>,
    ms: usize,
    config: &AcquisitionConfig,
    dc: [f32; 2],
) -> Tone {
    let fs = config.sample_rate_hz;
    let mut f = config.intermediate_frequency_hz + f64::from(f_hz);
    let refine = REFINE_MS.min(ms).max(1);
    for _ in 0..REFINE_STEPS {
        let tone = Tone {
            step: CarrierNco::step_for(f, fs),
        };
        let mut turn = [0.0f64; 2];
        let mut previous = tone.phasor(0, samples, config, dc);
        for m in 1..refine {
            let a = tone.phasor(m, samples, config, dc);
            turn[0] += f64::from(a[0] * previous[0] + a[1] * previous[1]);
            turn[1] += f64::from(a[1] * previous[0] - a[0] * previous[1]);
            previous = a;
        }
        f += libm::atan2(turn[1], turn[0]) / core::f64::consts::TAU * 1000.0;
    }
    Tone {
        step: CarrierNco::step_for(f, fs),
    }
}
