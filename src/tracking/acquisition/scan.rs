//! The code × Doppler scan of the search and of the verification dwell, the background
//! statistics, the refinement of the peak.

use super::cancel::MAX_CANCELLED;
use super::input::BinClock;
use super::tone::{rotate, MAX_TONES};
use super::{
    Acquisition, AcquisitionConfig, SearchSamples, Verification, FLOOR_GUARD_CHIPS,
    MAX_DOPPLER_BINS, VERIFICATION_CODE_WINDOW_CHIPS, VERIFICATION_FALSE_ALARM,
};
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ, CA_CODE_LENGTH, GPS_L1_HZ};
use crate::signal::nco::{carrier_index, CarrierNco, COS_TABLE, SIN_TABLE};
use crate::tracking::fft::Complex;

/// Sub-samples per code bin when the code is integrated into the `N` bins.
const CODE_SUBSAMPLES: usize = 8;

/// A spectral line of one millisecond's samples above this many times the background line
/// power is interference (a tone): it is removed with its leakage before the correlation.
/// Thermal noise exceeds it with probability `e^{−15}` = 3·10⁻⁷ per line; satellites spread
/// their power over a thousand lines and stay below it up to 60 dB-Hz.
pub const EXCISION_FACTOR: f32 = 15.0;

/// Most interference lines removed per millisecond (the strongest first; a tone becomes a
/// comb of lines through the integrate-and-dump's uneven sample counts per bin).
const MAX_EXCISED_LINES: usize = 32;

/// Steps of the trimmed mean that estimates the background line power.
const LEVEL_STEPS: usize = 4;

/// Standard errors below `K` within which the background's effective number of milliseconds
/// counts as `K` (thermal noise keeps the classic threshold).
const K_TOLERANCE_SE: f64 = 2.0;

/// Doppler bins of the verification dwell (the refined Doppler and ± half a step).
const DWELL_BINS: usize = 3;

/// Which Dopplers a scan covers, from which millisecond of the samples.
#[derive(Clone, Copy, Debug)]
pub(super) struct Grid {
    /// Doppler of bin 0, Hz.
    first_hz: f32,
    /// Bin spacing, Hz.
    step_hz: f32,
    /// Number of bins.
    bins: usize,
    /// First millisecond of the samples the scan sums.
    first_ms: usize,
}

impl Grid {
    /// The search's grid: `centre ± doppler_max` in `doppler_step` bins over the first `K` ms.
    pub(super) fn search(config: &AcquisitionConfig, centre_hz: f32) -> Self {
        let bins = config.doppler_bins();
        Self {
            first_hz: centre_hz - (bins / 2) as f32 * config.doppler_step_hz,
            step_hz: config.doppler_step_hz,
            bins,
            first_ms: 0,
        }
    }

    /// The dwell's grid: `doppler` and ± half a step over milliseconds `K..2K`.
    fn dwell(config: &AcquisitionConfig, doppler: f32) -> Self {
        Self {
            first_hz: doppler - 0.5 * config.doppler_step_hz,
            step_hz: 0.5 * config.doppler_step_hz,
            bins: DWELL_BINS,
            first_ms: usize::from(config.noncoherent_ms),
        }
    }

    fn doppler(&self, bin: usize) -> f32 {
        self.first_hz + bin as f32 * self.step_hz
    }
}

/// The strongest cell of a scan (within its code window).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Peak {
    /// Power, engine units.
    pub(super) power: f32,
    /// Doppler bin.
    bin: usize,
    /// Code bin (lag).
    lag: usize,
    /// Powers of the code bins before and after.
    neighbours: [f32; 2],
}

/// Sums over the background cells (away from each Doppler bin's peak).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Floor {
    sum: f64,
    sum_sq: f64,
    count: u64,
}

impl Floor {
    /// Adds one Doppler bin's cells except those within `guard` bins of `peak_at`: f32 sums
    /// within the bin (the target has no double-precision unit), the squares scaled by the
    /// bin's mean so that they stay far inside f32's range, f64 across bins. The background
    /// is the circular run of `n − 2·guard − 1` cells after the guard band: two slices,
    /// no test per cell.
    fn add_bin(&mut self, power: &[f32], peak_at: usize, guard: usize) {
        let n = power.len();
        let Some(len) = n.checked_sub(guard.saturating_mul(2).saturating_add(1)) else {
            return;
        };
        let start = (peak_at % n.max(1)).saturating_add(guard).saturating_add(1) % n.max(1);
        let first_len = len.min(n - start);
        let (first, second) = (
            power
                .get(start..start.saturating_add(first_len))
                .unwrap_or(&[]),
            power.get(..len.saturating_sub(first_len)).unwrap_or(&[]),
        );
        let cells = || first.iter().chain(second.iter());
        let sum: f32 = first.iter().sum::<f32>() + second.iter().sum::<f32>();
        // (at most n ≤ 8192 cells)
        let count = len as u32;
        // (a statistics count over bins: saturates rather than wraps)
        if count == 0 || !(sum > 0.0) {
            self.count = self.count.saturating_add(u64::from(count));
            return;
        }
        let scale = count as f32 / sum;
        let sum_sq: f32 = cells().map(|&p| (p * scale) * (p * scale)).sum();
        let unscale = f64::from(sum) / f64::from(count);
        self.sum += f64::from(sum);
        self.sum_sq += f64::from(sum_sq) * unscale * unscale;
        self.count = self.count.saturating_add(u64::from(count));
    }

    /// Mean background cell (0 without cells).
    pub(super) fn mean(&self) -> f32 {
        if self.count == 0 {
            0.0
        } else {
            (self.sum / self.count as f64) as f32
        }
    }

    /// `⌊μ²/σ²⌋` clamped to `1..=k` (`k` for a background without spread, 1 without cells).
    /// A ratio within [`K_TOLERANCE_SE`] standard errors below `k` counts as `k`: on thermal
    /// noise the estimate scatters around `k` (standard error `k √((2 + 6/k)/n)` for `n`
    /// cells, half of them independent), and the classic threshold is kept.
    pub(super) fn effective_ms(&self, k: u16) -> u16 {
        if self.count < 2 {
            return 1;
        }
        let n = self.count as f64;
        let mean = self.sum / n;
        let var = (self.sum_sq / n - mean * mean).max(0.0);
        if !(mean > 0.0) {
            return 1;
        }
        let k_f = f64::from(k.max(1));
        let se = k_f * libm::sqrt((2.0 + 6.0 / k_f) / (0.5 * n));
        if !(var > 0.0) || mean * mean / var >= k_f - K_TOLERANCE_SE * se {
            return k.max(1);
        }
        let ratio = libm::floor(mean * mean / var);
        if ratio >= 1.0 {
            ratio as u16
        } else {
            1
        }
    }
}

/// The outcome of a verification dwell.
#[derive(Clone, Copy, Debug)]
pub(super) struct Dwell {
    pub(super) verification: Verification,
    pub(super) metric: f32,
    pub(super) threshold: f32,
}

impl Dwell {
    pub(super) fn not_tested() -> Self {
        Self {
            verification: Verification::NotTested,
            metric: 0.0,
            threshold: 0.0,
        }
    }
}

/// The circular distance of two lags `d` apart among `n` (`d` itself when `d > n`: not a lag
/// difference, so not wrapped).
fn circular(d: usize, n: usize) -> usize {
    n.checked_sub(d).map_or(d, |r| d.min(r))
}

/// A code window for the peak search: centre lag and half-width, bins.
#[derive(Clone, Copy, Debug)]
pub(super) struct CodeWindow {
    centre: usize,
    half: usize,
}

impl CodeWindow {
    fn contains(&self, lag: usize, n: usize) -> bool {
        let d = lag.abs_diff(self.centre);
        circular(d, n) <= self.half
    }
}

impl<const N: usize, const L: usize> Acquisition<N, L> {
    /// The code of `prn` integrated over the `N` bins of one code period, transformed (in
    /// `self.work`) and kept as the half of its spectrum that a real sequence's holds
    /// ([`pack_real_spectrum`]).
    pub(super) fn prepare_code(&mut self, prn: Prn) {
        for (b, c) in self.work.iter_mut().enumerate() {
            *c = [integrated_chip::<N>(prn, b), 0.0];
        }
        self.fft.forward(&mut self.work);
        pack_real_spectrum(&self.work, &mut self.code);
    }

    /// Scans the grid's Doppler bins: the strongest cell (within `window` if given), and the
    /// background statistics; fills `self.peaks` with each bin's strongest cell.
    ///
    /// The bins are taken in chunks of up to `L` that share one sub-bin offset (their Doppler
    /// modulo the FFT's 1 kHz line spacing): one mix and one forward FFT of each millisecond
    /// serve the whole chunk, each bin a circular shift of that spectrum by its whole number
    /// of kHz ([`Acquisition::accumulate_chunk`]).
    pub(super) fn scan(
        &mut self,
        samples: SearchSamples<'_>,
        grid: &Grid,
        window: Option<CodeWindow>,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> (Peak, Floor) {
        let guard = libm::ceilf(FLOOR_GUARD_CHIPS * N as f32 / CA_CODE_LENGTH as f32) as usize;
        let mut best = Peak::default();
        let mut floor = Floor::default();
        let mut done = [false; MAX_DOPPLER_BINS];
        let bins = grid.bins.min(MAX_DOPPLER_BINS);
        for first in 0..bins {
            let chunk = take_chunk::<L>(grid, first, bins, &mut done);
            let Some(&(_, offset, _)) = chunk.bins().first() else {
                continue;
            };
            self.accumulate_chunk(samples, grid, offset, chunk.bins(), config, dc);
            for (lane, &(b, _, _)) in self.lanes.iter().zip(chunk.bins()) {
                let (local, local_at, top, top_at) = strongest(lane, window);
                if let Some(slot) = self.peaks.get_mut(b) {
                    *slot = (local, local_at as u32);
                }
                floor.add_bin(lane, local_at, guard);
                // (ties keep the lower bin, as a scan in bin order would)
                let better = top > best.power || (top == best.power && b < best.bin);
                if let Some(at) = top_at.filter(|_| better && top > 0.0) {
                    best = Peak {
                        power: top,
                        bin: b,
                        lag: at,
                        // (circular lags, N a power of two: wrapping is the modulo)
                        neighbours: [
                            lane[at.wrapping_sub(1) & (N - 1)],
                            lane[at.wrapping_add(1) & (N - 1)],
                        ],
                    };
                }
            }
        }
        (best, floor)
    }

    /// One Doppler `doppler` over the first `K` ms: the strongest cell within one code bin of
    /// lag `centre` (`interpolate`: with the correlation triangle's peak interpolated), and
    /// the mean background cell (away from the bin's peak). Needs the code prepared.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn measure_at(
        &mut self,
        samples: SearchSamples<'_>,
        doppler: f32,
        centre: usize,
        interpolate: bool,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> (f32, f32) {
        let grid = Grid {
            first_hz: doppler,
            step_hz: 0.0,
            bins: 1,
            first_ms: 0,
        };
        let window = CodeWindow { centre, half: 1 };
        let (peak, floor) = self.scan(samples, &grid, Some(window), config, dc);
        if !interpolate {
            return (peak.power, floor.mean());
        }
        let (a0, am, ap) = (
            crate::sqrtf(peak.power),
            crate::sqrtf(peak.neighbours[0]),
            crate::sqrtf(peak.neighbours[1]),
        );
        // Triangle of half-width one chip sampled every 1023/N chips: the peak is
        // a0 / (1 − |δ|·1023/N) for an offset of δ bins.
        let denom = 2.0 * (a0 - am.min(ap));
        let delta = if denom > 0.0 {
            ((ap - am) / denom).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        let a = a0 / (1.0 - delta.abs() * CA_CODE_LENGTH as f32 / N as f32);
        (a * a, floor.mean())
    }

    /// The lanes ← the `K`-ms non-coherent sums of the correlation at the chunk's Dopplers
    /// from the grid's first millisecond, each millisecond shifted by its code Doppler.
    /// Per millisecond: one mix at the common sub-bin `offset` and one forward FFT; per bin,
    /// the spectrum product at the bin's line shift, one FFT and the power sum.
    #[allow(clippy::too_many_arguments)]
    fn accumulate_chunk(
        &mut self,
        samples: SearchSamples<'_>,
        grid: &Grid,
        offset: f32,
        chunk: &[(usize, f32, i32)],
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) {
        for lane in self.lanes.iter_mut().take(chunk.len()) {
            *lane = [0.0; N];
        }
        for m in 0..usize::from(config.noncoherent_ms) {
            self.decimate(samples, grid.first_ms.saturating_add(m), offset, config, dc);
            self.fft.forward(&mut self.data);
            self.excise();
            for (lane, &(b, _, lines)) in self.lanes.iter_mut().zip(chunk) {
                correlate_shifted(&self.data, &self.code, lines, &mut self.work);
                self.fft.forward(&mut self.work);
                add_power(lane, &self.work, code_drift::<N>(m, grid.doppler(b)));
            }
        }
    }

    /// The reference for [`Acquisition::accumulate_chunk`]: the samples mixed with each bin's
    /// own Doppler and transformed again for every bin (the search before the shared FFT).
    #[cfg(test)]
    pub(super) fn accumulate_remix(
        &mut self,
        samples: SearchSamples<'_>,
        doppler: f32,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> [f32; N] {
        let mut power = [0.0f32; N];
        for m in 0..usize::from(config.noncoherent_ms) {
            self.decimate(samples, m, doppler, config, dc);
            self.fft.transform(&mut self.data, false);
            self.excise();
            unpack_real_spectrum(&self.code, &mut self.work);
            for (d, c) in self.data.iter_mut().zip(self.work.iter()) {
                // X · conj(C)
                *d = [d[0] * c[0] + d[1] * c[1], d[1] * c[0] - d[0] * c[1]];
            }
            self.fft.transform(&mut self.data, true);
            add_power(&mut power, &self.data, code_drift::<N>(m, doppler));
        }
        power
    }

    /// Prepares the interference handling for these samples: the tones to cancel
    /// ([`super::tone`]) and the background line power of the spectrum after their
    /// cancellation, for [`Acquisition::excise`] (0 for silent samples, and when no line
    /// of millisecond 0 stands out: nothing to excise). Clears the cancelled signals.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub(super) fn prepare_interference(
        &mut self,
        samples: SearchSamples<'_>,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) {
        self.level = 0.0;
        self.tone_count = 0;
        self.cancelled_count = 0;
        let level = self.spectrum_level(samples, config, dc);
        let level = if self.find_tones(samples, level, config, dc) > 0 {
            self.spectrum_level(samples, config, dc)
        } else {
            level
        };
        // Excision only where the spectrum (after the tones' cancellation) has a line to
        // remove: none costs nothing per millisecond.
        let limit = EXCISION_FACTOR * level;
        let lines = self.data.iter().any(|d| d[0] * d[0] + d[1] * d[1] > limit);
        self.level = if lines { level } else { 0.0 };
    }

    /// The background line power of the IF-mixed spectrum of millisecond 0 (left in
    /// `self.data`): a mean trimmed of the lines above [`EXCISION_FACTOR`] times it
    /// ([`LEVEL_STEPS`] steps).
    fn spectrum_level(
        &mut self,
        samples: SearchSamples<'_>,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> f32 {
        self.decimate(samples, 0, 0.0, config, dc);
        self.fft.transform(&mut self.data, false);
        let mut level = f32::INFINITY;
        for _ in 0..LEVEL_STEPS {
            let (mut sum, mut count) = (0.0f32, 0u32);
            for d in &self.data {
                let p = d[0] * d[0] + d[1] * d[1];
                if p <= EXCISION_FACTOR * level {
                    sum += p;
                    // (at most one per line: never saturates)
                    count = count.saturating_add(1);
                }
            }
            level = if count > 0 { sum / count as f32 } else { 0.0 };
        }
        level
    }

    /// Removes the interference lines from the spectrum in `self.data`: every local maximum
    /// above [`EXCISION_FACTOR`] times the background level (up to [`MAX_EXCISED_LINES`],
    /// strongest first), with the lines within `√(P/level)/π` of it (a rectangular window's
    /// leakage `P/(πk)²` falls below the background there), at most `N/8` either side.
    fn excise(&mut self) {
        let level = self.level;
        if !(level > 0.0) {
            return;
        }
        let power = |d: &Complex| d[0] * d[0] + d[1] * d[1];
        let limit = EXCISION_FACTOR * level;
        let mut lines = [(0.0f32, 0usize); MAX_EXCISED_LINES];
        // Rolling powers of lines k − 1, k, k + 1 (each computed once).
        let (mut before, mut p) = (power(&self.data[N - 1]), power(&self.data[0]));
        for k in 0..N {
            let after = power(&self.data[(k + 1) & (N - 1)]);
            if p > limit && p >= before && p > after {
                // Keep the strongest: replace the weakest kept line.
                let weakest = lines.iter_mut().min_by(|a, b| a.0.total_cmp(&b.0));
                if let Some(w) = weakest.filter(|w| p > w.0) {
                    *w = (p, k);
                }
            }
            (before, p) = (p, after);
        }
        for &(p, k) in lines.iter().filter(|l| l.0 > 0.0) {
            let half = libm::ceilf(crate::sqrtf(p / level) / core::f32::consts::PI) as usize;
            let half = half.min(N / 8);
            for j in 0..=2 * half {
                // (circular lines, N a power of two: wrapping is the modulo)
                let at = k.wrapping_add(j).wrapping_sub(half) & (N - 1);
                if let Some(d) = self.data.get_mut(at) {
                    *d = [0.0; 2];
                }
            }
        }
    }

    /// Mixes millisecond `m` of the samples (mean `dc` and the tones removed) with the Doppler
    /// bin's carrier and integrates it into the `N` bins of `self.data`.
    fn decimate(
        &mut self,
        samples: SearchSamples<'_>,
        m: usize,
        doppler: f32,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) {
        self.data = [[0.0; 2]; N];
        let fs = config.sample_rate_hz;
        let start = config.ms_start(m);
        let end = config.ms_start(m.saturating_add(1)).min(samples.len());
        let step = CarrierNco::step_for(config.intermediate_frequency_hz + f64::from(doppler), fs);
        // Bin of sample k: floor((k/f_s − m·1 ms) · N · 1000), in 32.32 fixed point.
        let bin_step = libm::round(N as f64 * 1000.0 / fs * 4_294_967_296.0) as u64;
        let t0 = (start as f64 / fs - m as f64 * 1e-3) * N as f64 * 1000.0;
        let mut bin_acc = libm::round(t0 * 4_294_967_296.0) as u64;
        let mut phase = 0u32;
        let dq = if samples.is_complex() { dc[1] } else { 0.0 };
        let tones = self.tones.get(..self.tone_count).unwrap_or(&[]);
        let mut tone_phase = [0u32; MAX_TONES];
        let mut phasors = [[0.0f32; 2]; MAX_TONES];
        for ((p, a), t) in tone_phase.iter_mut().zip(phasors.iter_mut()).zip(tones) {
            *p = t.step().wrapping_mul(start as u32);
            *a = t.phasor(m, samples, config, dc);
        }
        // The known signals cancelled: each one's phasor over this millisecond, and its
        // replica's phase words at the first sample.
        let cancelled = self.cancelled.get(..self.cancelled_count).unwrap_or(&[]);
        let mut replicas = [(0u32, 0u64, [0.0f32; 2]); MAX_CANCELLED];
        for (r, c) in replicas.iter_mut().zip(cancelled) {
            let (carrier, code) = c.at(start);
            *r = (carrier, code, c.phasor(m, samples, config, dc));
        }
        if tones.is_empty() && cancelled.is_empty() {
            // (the common case: nothing to cancel, one tight pass)
            let data = &mut self.data;
            if let Some(mut mix) = BinMix::new(step, bin_acc, bin_step, N) {
                let clock = BinClock {
                    acc: bin_acc,
                    step: bin_step,
                };
                samples.for_each_bin_sum(start..end, [dc[0], dq], clock, |n, x, y| {
                    mix.add_run(data, n, x, y);
                });
                return;
            }
            let mut nco = MixNco {
                phase: 0,
                step,
                bin_acc,
                bin_step,
            };
            samples.for_each_centred(start..end, [dc[0], dq], |x, y| nco.mix(data, x, y));
            return;
        }
        let complex = samples.is_complex();
        let data = &mut self.data;
        samples.for_each_centred(start..end, [dc[0], dq], |mut x, mut y| {
            for ((p, a), t) in tone_phase.iter_mut().zip(&phasors).zip(tones) {
                let v = rotate(*a, *p);
                x -= v[0];
                if complex {
                    y -= v[1];
                }
                *p = p.wrapping_add(t.step());
            }
            for ((carrier, code, a), c) in replicas.iter_mut().zip(cancelled) {
                let v = rotate(*a, *carrier);
                let chip = c.chip(*code);
                x -= chip * v[0];
                if complex {
                    y -= chip * v[1];
                }
                c.step(carrier, code);
            }
            let bin = ((bin_acc >> 32) as usize) & (N - 1);
            add_mixed(&mut data[bin], x, y, phase);
            phase = phase.wrapping_add(step);
            // (32.32 fixed point: the bin is (bin_acc >> 32) mod N, which wrapping keeps)
            bin_acc = bin_acc.wrapping_add(bin_step);
        });
    }

    /// Refined Doppler (Hz) and code phase (chips at the first sample) of a search peak.
    pub(super) fn refine(&self, peak: &Peak, grid: &Grid) -> (f32, f32) {
        // Code phase: triangle interpolation on amplitudes; lag ℓ means phase (N − ℓ)·1023/N.
        let (a0, am, ap) = (
            crate::sqrtf(peak.power),
            crate::sqrtf(peak.neighbours[0]),
            crate::sqrtf(peak.neighbours[1]),
        );
        let denom = 2.0 * (a0 - am.min(ap));
        let delta = if denom > 0.0 {
            ((ap - am) / denom).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        let lag = peak.lag as f32 + delta;
        let len = CA_CODE_LENGTH as f32;
        let mut code_phase = (N as f32 - lag) * (len / N as f32);
        code_phase -= libm::floorf(code_phase / len) * len;
        // Doppler: parabola through the neighbouring bins' peak amplitudes.
        let amp = |b: usize| self.peaks.get(b).map_or(0.0, |p| crate::sqrtf(p.0));
        let bd = peak.bin;
        let (fm, f0, fp) = (
            if bd > 0 { amp(bd - 1) } else { 0.0 },
            amp(bd),
            if bd < grid.bins.saturating_sub(1) {
                amp(bd + 1)
            } else {
                0.0
            },
        );
        let curv = 2.0 * f0 - fm - fp;
        let df = if curv > 0.0 {
            (0.5 * (fp - fm) / curv).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        (grid.doppler(bd) + df * grid.step_hz, code_phase)
    }

    /// The verification dwell of a candidate of `prn` at `doppler` and `code_phase` (chips at
    /// the first sample) on milliseconds `K..2K`, with the search's `effective_ms` as a
    /// ceiling.
    ///
    /// Without interference to excise, the dwell's few cells are direct correlations
    /// ([`Acquisition::scan_window`]): per millisecond and bin one mix and
    /// `2·⌈N/1023⌉ + 1` products of `N` points instead of two FFTs, and its background
    /// the samples' own noise power, its effective milliseconds the search's.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn verify(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        doppler: f32,
        code_phase: f32,
        effective_ms: u16,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> Dwell {
        if samples.len() < config.samples_needed() {
            return Dwell {
                verification: Verification::NoSamples,
                ..Dwell::not_tested()
            };
        }
        // The code phase the candidate predicts at the dwell's first sample, as a lag.
        let start = config.ms_start(usize::from(config.noncoherent_ms));
        let rate = CA_CHIP_RATE_HZ * (1.0 + f64::from(doppler) / GPS_L1_HZ);
        let len = CA_CODE_LENGTH as f64;
        let phase = f64::from(code_phase) + start as f64 / config.sample_rate_hz * rate;
        let phase = phase - libm::floor(phase / len) * len;
        let centre = libm::round(N as f64 * (1.0 - phase / len)) as usize & (N - 1);
        let half =
            libm::ceilf(VERIFICATION_CODE_WINDOW_CHIPS * N as f32 / CA_CODE_LENGTH as f32) as usize;
        let grid = Grid::dwell(config, doppler);
        let window = CodeWindow { centre, half };
        let (power, mean, k) = if self.level > 0.0 {
            // (the interference is excised from the spectrum: the dwell's FFT scan)
            let (peak, floor) = self.scan(samples, &grid, Some(window), config, dc);
            let k = floor.effective_ms(config.noncoherent_ms).min(effective_ms);
            (peak.power, floor.mean(), k)
        } else {
            let (power, mean) = self.scan_window(prn, samples, &grid, window, config, dc);
            (power, mean, effective_ms)
        };
        let cells = (DWELL_BINS * (2 * half + 1)) as f64;
        let threshold = self.threshold(k, cells, VERIFICATION_FALSE_ALARM);
        let metric = if mean > 0.0 { power / mean } else { 0.0 };
        Dwell {
            verification: if metric > threshold {
                Verification::Passed
            } else {
                Verification::Failed
            },
            metric,
            threshold,
        }
    }
}

impl<const N: usize, const L: usize> Acquisition<N, L> {
    /// The strongest cell of a grid within `window` by direct correlation of each
    /// millisecond's bins with the code of `prn` at the window's lags, and the mean cell that
    /// the samples' noise alone gives: a cell of a millisecond whose bins `x` hold white noise
    /// has `E|Σ x[j + ℓ]·c[j]|² = (Σ|x|²)(Σc²)/N` on average over the lags. The cells are
    /// the FFT scan's divided by `N²`: the same ratio.
    ///
    /// A signal's own power counts as noise there (+1 % at 40 dB-Hz, +10 % at 50 dB-Hz:
    /// a strong signal passes anyway), so the test can only be stricter for it.
    fn scan_window(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        grid: &Grid,
        window: CodeWindow,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> (f32, f32) {
        // (the lanes are idle during a dwell: the first holds the code's bins)
        let Some(code) = self.lanes.first_mut() else {
            return (0.0, 0.0);
        };
        for (b, c) in code.iter_mut().enumerate() {
            *c = integrated_chip::<N>(prn, b);
        }
        let code_energy: f32 = code.iter().map(|c| c * c).sum();
        let lags = window.half.saturating_mul(2).saturating_add(1);
        let first_lag = window.centre.wrapping_sub(window.half);
        let (mut best, mut noise) = (0.0f32, 0.0f32);
        for b in 0..grid.bins {
            let mut cells = [0.0f32; MAX_WINDOW_LAGS];
            let doppler = grid.doppler(b);
            for m in 0..usize::from(config.noncoherent_ms) {
                self.decimate(
                    samples,
                    grid.first_ms.saturating_add(m),
                    doppler,
                    config,
                    dc,
                );
                let Some(code) = self.lanes.first() else {
                    return (0.0, 0.0);
                };
                noise += self
                    .data
                    .iter()
                    .map(|d| d[0] * d[0] + d[1] * d[1])
                    .sum::<f32>();
                // (as add_power: cell ℓ sums ms m's correlation at lag ℓ − drift)
                let drift = code_drift::<N>(m, doppler);
                for (j, cell) in (0..lags).zip(cells.iter_mut()) {
                    let lag = first_lag.wrapping_add(j).wrapping_sub(drift) & (N - 1);
                    let r = correlate_at(&self.data, code, lag);
                    *cell += r[0] * r[0] + r[1] * r[1];
                }
            }
            best = cells.iter().fold(best, |a, &c| a.max(c));
        }
        let mean = noise * code_energy / (N as f32 * grid.bins.max(1) as f32);
        (best, mean)
    }
}

/// Most lags of a dwell's code window: `2·⌈N/1023⌉ + 1` for `N` up to 8192.
const MAX_WINDOW_LAGS: usize = 19;

/// The code of `prn` integrated over bin `b` of the `N` bins of one code period: the mean of
/// [`CODE_SUBSAMPLES`] chips across the bin, in `−1 … 1`.
#[inline]
fn integrated_chip<const N: usize>(prn: Prn, b: usize) -> f32 {
    let mut s = 0i32;
    // (b < N ≤ 8192: the products stay far inside usize, the sum within ±8)
    for k in 0..CODE_SUBSAMPLES {
        let sub = b.wrapping_mul(CODE_SUBSAMPLES).wrapping_add(k);
        let chip = sub.wrapping_mul(CA_CODE_LENGTH) / (N * CODE_SUBSAMPLES);
        s = s.wrapping_add(i32::from(prn.chip(chip)));
    }
    s as f32 / CODE_SUBSAMPLES as f32
}

/// The code Doppler's lag drift of millisecond `m` at `doppler` (Hz), bins modulo `N`:
/// `m·N·f/f_L1` rounded.
fn code_drift<const N: usize>(m: usize, doppler: f32) -> usize {
    let drift = libm::round(m as f64 * N as f64 * f64::from(doppler) / GPS_L1_HZ) as i64;
    drift.rem_euclid(N as i64) as usize
}

/// `Σ_j x[j + lag]·c[j]` (indices modulo `N`): the correlation at one lag, as the FFT scan's
/// cell `lag` up to the factor `N`.
fn correlate_at<const N: usize>(x: &[Complex; N], code: &[f32; N], lag: usize) -> Complex {
    let s = lag.min(N);
    let (x_head, x_tail) = x.split_at(s);
    let (code_head, code_tail) = code.split_at(N - s);
    let mut acc = [0.0f32; 2];
    for (runs_x, runs_code) in [(x_tail, code_head), (x_head, code_tail)] {
        for (d, &c) in runs_x.iter().zip(runs_code) {
            acc[0] += d[0] * c;
            acc[1] += d[1] * c;
        }
    }
    acc
}

/// The strongest cell of a bin (power, lag) and the strongest within `window` (the same
/// without a window; `None` when no cell of the window is above 0).
fn strongest<const N: usize>(
    power: &[f32; N],
    window: Option<CodeWindow>,
) -> (f32, usize, f32, Option<usize>) {
    let (mut local, mut local_at) = (0.0f32, 0usize);
    for (l, &p) in power.iter().enumerate() {
        if p > local {
            (local, local_at) = (p, l);
        }
    }
    let Some(w) = window else {
        return (local, local_at, local, (local > 0.0).then_some(local_at));
    };
    let (mut top, mut top_at) = (0.0f32, None);
    for (l, &p) in power.iter().enumerate() {
        if p > top && w.contains(l, N) {
            (top, top_at) = (p, Some(l));
        }
    }
    (local, local_at, top, top_at)
}

/// `d += (x + jy) · e^{−jφ}`, the carrier's phase `φ` a 32-bit word (the NCO's table).
#[inline(always)]
fn add_mixed(d: &mut Complex, x: f32, y: f32, phase: u32) {
    let idx = carrier_index(phase);
    let (c, s) = (f32::from(COS_TABLE[idx]), f32::from(SIN_TABLE[idx]));
    d[0] += x * c + y * s;
    d[1] += y * c - x * s;
}

/// The carrier and bin counters of one millisecond's mix (see [`Acquisition::decimate`]).
struct MixNco {
    phase: u32,
    step: u32,
    bin_acc: u64,
    bin_step: u64,
}

impl MixNco {
    /// Mixes one `(I, Q)` sample (less the mean) with the carrier and integrates it into its
    /// bin.
    #[inline(always)]
    fn mix<const N: usize>(&mut self, data: &mut [Complex; N], x: f32, y: f32) {
        // (32.32 fixed point: the bin is (bin_acc >> 32) mod N, which wrapping keeps)
        let bin = ((self.bin_acc >> 32) as usize) & (N - 1);
        if let Some(d) = data.get_mut(bin) {
            add_mixed(d, x, y, self.phase);
        }
        self.phase = self.phase.wrapping_add(self.step);
        self.bin_acc = self.bin_acc.wrapping_add(self.bin_step);
    }
}

/// The most the carrier of a Doppler bin may turn over one of the `N` bins of a millisecond
/// for [`BinMix`] to mix it, cycles: up to `N · 1000 / 16` Hz (64 kHz at `N` = 1024),
/// a complex front end's LEO Doppler at zero IF. Mixing a bin's samples at their middle's
/// phase then loses at most `1 − sinc²(1/16)` = 1.3 % of a signal's power (0.06 dB) against
/// mixing each sample at its own.
const BIN_MIX_MAX_TURN: f64 = 1.0 / 16.0;

/// One millisecond's mix at the bin rate: each bin's samples summed first
/// ([`SearchSamples::for_each_bin_sum`]), the sum turned once by the carrier's phase at the
/// bin's middle sample ([`BIN_MIX_MAX_TURN`]). On bit planes at 2.6 Msps a bin's sums are
/// table lookups: the millisecond costs about half of [`MixNco`]'s sample by sample.
struct BinMix {
    /// Carrier phase of the run's first sample and its step per sample.
    phase: u32,
    step: u32,
    /// The run's bin (each run is the next bin's samples).
    bin: usize,
}

impl BinMix {
    /// The bin-rate mix of a carrier stepping `step` per sample, its bins counted from
    /// `bin_acc` by `bin_step` (as [`MixNco`]'s); `None` when the carrier turns more than
    /// [`BIN_MIX_MAX_TURN`] over a bin, or a bin holds less than a sample.
    fn new(step: u32, bin_acc: u64, bin_step: u64, n: usize) -> Option<Self> {
        let cycles_per_sample = f64::from((step as i32).unsigned_abs()) / 4_294_967_296.0;
        let samples_per_bin = 4_294_967_296.0 / bin_step as f64;
        let worth = samples_per_bin > 1.0 && n > 1;
        (worth && cycles_per_sample * samples_per_bin <= BIN_MIX_MAX_TURN).then_some(Self {
            phase: 0,
            step,
            bin: ((bin_acc >> 32) as usize) & n.saturating_sub(1),
        })
    }

    /// Mixes the sum `(x, y)` of a run of `n` samples of one bin (less the mean) at the
    /// phase of its middle sample into `data`.
    #[inline(always)]
    fn add_run<const N: usize>(&mut self, data: &mut [Complex; N], n: u32, x: f32, y: f32) {
        // first + step · (n − 1) / 2, the half taken on the signed turn
        let half_turn = (self.step.wrapping_mul(n.wrapping_sub(1)) as i32) >> 1;
        if let Some(d) = data.get_mut(self.bin) {
            add_mixed(d, x, y, self.phase.wrapping_add(half_turn as u32));
        }
        self.phase = self.phase.wrapping_add(self.step.wrapping_mul(n));
        self.bin = self.bin.wrapping_add(1) & (N - 1);
    }
}

/// The FFT's line spacing for one millisecond of `N` bins, Hz.
const LINE_HZ: f32 = 1000.0;

/// Two Dopplers closer than this share a sub-bin offset, Hz.
const OFFSET_TOLERANCE_HZ: f32 = 0.01;

/// A Doppler `f` (Hz) as a sub-bin offset (Hz, in `[−500, 500)`) and whole FFT lines:
/// `f = offset + lines · 1 kHz` (half-kHz Dopplers all get offset −500 Hz, so that they
/// share one spectrum).
pub(super) fn split_doppler(f: f32) -> (f32, i32) {
    // (|f| ≤ the validated span: far inside i32; the cast saturates anyway)
    let lines = libm::floorf(f / LINE_HZ + 0.5) as i32;
    (f - lines as f32 * LINE_HZ, lines)
}

/// Up to `L` bins of a grid (index, offset, lines) that share one sub-bin offset.
struct Chunk<const L: usize> {
    bins: [(usize, f32, i32); L],
    count: usize,
}

impl<const L: usize> Chunk<L> {
    fn bins(&self) -> &[(usize, f32, i32)] {
        self.bins.get(..self.count).unwrap_or(&[])
    }
}

/// The next chunk: bin `first` (unless done) and the following bins not yet done with its
/// sub-bin offset, up to `L`; marks them done.
fn take_chunk<const L: usize>(
    grid: &Grid,
    first: usize,
    bins: usize,
    done: &mut [bool; MAX_DOPPLER_BINS],
) -> Chunk<L> {
    let mut chunk = Chunk {
        bins: [(0, 0.0, 0); L],
        count: 0,
    };
    if done.get(first).is_none_or(|&d| d) {
        return chunk;
    }
    let (offset, _) = split_doppler(grid.doppler(first));
    let rest = done.get_mut(first..bins.max(first)).unwrap_or(&mut []);
    for (j, d) in rest.iter_mut().enumerate() {
        if chunk.count >= L {
            break;
        }
        // (first + j < bins ≤ MAX_DOPPLER_BINS: no wrap)
        let b = first.wrapping_add(j);
        let (o, lines) = split_doppler(grid.doppler(b));
        if !*d && (o - offset).abs() <= OFFSET_TOLERANCE_HZ {
            if let Some(slot) = chunk.bins.get_mut(chunk.count) {
                *slot = (b, offset, lines);
                chunk.count = chunk.count.saturating_add(1);
                *d = true;
            }
        }
    }
    chunk
}

/// `out[k] = conj(X[k + lines]) · C[k]` (indices modulo `N`): the conjugate of the product
/// `X_s · conj(C)` whose inverse FFT is the correlation at Doppler `offset + lines · 1 kHz`
/// (shifting the spectrum of the millisecond mixed at `offset` by `lines` lines is mixing it
/// with `e^{−j2π·lines·n/N}` more). Its forward FFT is the conjugate of that inverse FFT:
/// the same power, without conjugation passes.
fn correlate_shifted<const N: usize>(
    x: &[Complex; N],
    code: &[f32; N],
    lines: i32,
    out: &mut [Complex; N],
) {
    // the code's whole spectrum first, then each line multiplied in place
    unpack_real_spectrum(code, out);
    // (N ≤ 8192: the modulo is exact in i64)
    let s = i64::from(lines).rem_euclid(N as i64) as usize;
    let s = s.min(N);
    // out[..N − s] from x[s..], out[N − s..] from x[..s]: two straight runs
    let (x_head, x_tail) = x.split_at(s);
    let (out_a, out_b) = out.split_at_mut(N - s);
    for (runs_out, runs_x) in [(out_a, x_tail), (out_b, x_head)] {
        for (o, d) in runs_out.iter_mut().zip(runs_x) {
            let c = *o;
            *o = [d[0] * c[0] + d[1] * c[1], d[0] * c[1] - d[1] * c[0]];
        }
    }
}

/// The spectrum `x` of a real sequence of `N` points packed into `N` values: `X[N − k]` is
/// `conj(X[k])`, so `X[0]` and `X[N/2]` (real) and `X[1 … N/2 − 1]` hold it all, in
/// `[Re X[0], Re X[N/2], Re X[1], Im X[1], …]` (half the memory of the whole spectrum).
fn pack_real_spectrum<const N: usize>(x: &[Complex; N], packed: &mut [f32; N]) {
    let half = N / 2;
    let at = |k: usize| x.get(k).copied().unwrap_or([0.0; 2]);
    for (k, pair) in (0..half).zip(packed.chunks_exact_mut(2)) {
        let [re, im] = if k == 0 {
            [at(0)[0], at(half)[0]]
        } else {
            at(k)
        };
        pair.copy_from_slice(&[re, im]);
    }
}

/// `out` ← the whole spectrum that [`pack_real_spectrum`] packed.
fn unpack_real_spectrum<const N: usize>(packed: &[f32; N], out: &mut [Complex; N]) {
    let half = N / 2;
    let (low, high) = out.split_at_mut(half.min(N));
    for (k, (o, pair)) in (0..half).zip(low.iter_mut().zip(packed.chunks_exact(2))) {
        *o = if k == 0 {
            [pair[0], 0.0]
        } else {
            [pair[0], pair[1]]
        };
    }
    if let (Some(nyquist), Some(&re)) = (high.first_mut(), packed.get(1)) {
        *nyquist = [re, 0.0];
    }
    // X[N − k] = conj(X[k]) for k = 1 … N/2 − 1
    for (o, pair) in high
        .iter_mut()
        .skip(1)
        .zip(packed.chunks_exact(2).skip(1).rev())
    {
        *o = [pair[0], -pair[1]];
    }
}

/// `power[l] += |z[l − shift]|²` (circular lags).
fn add_power<const N: usize>(power: &mut [f32; N], z: &[Complex; N], shift: usize) {
    let s = shift.min(N);
    // lags l ≥ s read z[l − s]; lags l < s read z[N − s + l]
    let (low, high) = power.split_at_mut(s);
    let (z_head, z_tail) = z.split_at(N - s);
    for (p, d) in high.iter_mut().zip(z_head) {
        *p += d[0] * d[0] + d[1] * d[1];
    }
    for (p, d) in low.iter_mut().zip(z_tail) {
        *p += d[0] * d[0] + d[1] * d[1];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decoded complex samples for a search.
    fn cx<'a>(i: &'a [i8], q: &'a [i8]) -> SearchSamples<'a> {
        SearchSamples::decoded(i, Some(q)).unwrap()
    }
    use crate::noise::{SplitMix64, StandardNormal};
    use crate::tracking::fft::Fft;

    /// The bin-rate mix (each bin's samples summed, turned once at the bin's middle sample)
    /// keeps a carrier up to [`BIN_MIX_MAX_TURN`] (60 kHz at 2.6 Msps into 1024 bins) within
    /// 0.1 dB of its power at zero Doppler, where it is exact; past it, the search mixes
    /// sample by sample.
    #[test]
    fn the_bin_rate_mix_keeps_a_carrier_within_a_tenth_of_a_db() {
        const N: usize = 1024;
        const FS: f64 = 2.6e6;
        let config = AcquisitionConfig {
            sample_rate_hz: FS,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 50_000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 1,
            false_alarm_probability: 1e-3,
        };
        let mut engine = Acquisition::<N, 1>::new().unwrap();
        let mut power_at = |f: f64| {
            let (mut i, mut q) = ([0i8; 2601], [0i8; 2601]);
            for (k, (x, y)) in i.iter_mut().zip(q.iter_mut()).enumerate() {
                let a = 2.0 * core::f64::consts::PI * f * k as f64 / FS;
                (*x, *y) = (
                    (100.0 * a.cos()).round() as i8,
                    (100.0 * a.sin()).round() as i8,
                );
            }
            engine.decimate(cx(&i, &q), 0, f as f32, &config, [0.0; 2]);
            let sum = engine.data.iter().fold([0.0f64; 2], |s, d| {
                [s[0] + f64::from(d[0]), s[1] + f64::from(d[1])]
            });
            sum[0] * sum[0] + sum[1] * sum[1]
        };
        let at_zero = power_at(0.0);
        for f in [20_000.0, 45_000.0, 60_000.0, -60_000.0] {
            let loss_db = -10.0 * (power_at(f) / at_zero).log10();
            assert!(loss_db < 0.1, "{f} Hz: {loss_db} dB");
        }
        let bin_step = (N as f64 * 1000.0 / FS * 4_294_967_296.0).round() as u64;
        let mix = |f: f64| BinMix::new(CarrierNco::step_for(f, FS), 0, bin_step, N);
        assert!(mix(60_000.0).is_some() && mix(-60_000.0).is_some());
        assert!(mix(70_000.0).is_none() && mix(-70_000.0).is_none());
    }

    /// `N` standard normal points from `seed`: complex, or real (imaginary parts 0).
    fn gaussian_points<const N: usize>(seed: u64, complex: bool) -> [Complex; N] {
        let mut rng = SplitMix64::new(seed);
        let mut normal = StandardNormal::new();
        let mut x = [[0.0f32; 2]; N];
        for v in x.iter_mut() {
            let re = normal.sample(&mut rng);
            *v = [
                re,
                if complex {
                    normal.sample(&mut rng)
                } else {
                    0.0
                },
            ];
        }
        x
    }

    /// A real sequence's spectrum packed into half of it and unpacked is its whole spectrum:
    /// the lines `0 … N/2` as they were, the others their mirror's conjugates (equal to the
    /// transform's own to f32 rounding).
    #[test]
    fn a_real_spectrum_packs_into_half_and_back() {
        const N: usize = 1024;
        let fft = Fft::<N>::new().unwrap();
        let mut x = gaussian_points::<N>(5, false);
        fft.forward(&mut x);
        let (mut packed, mut whole) = ([0.0f32; N], [[0.0f32; 2]; N]);
        pack_real_spectrum(&x, &mut packed);
        unpack_real_spectrum(&packed, &mut whole);
        assert_eq!(whole[0], [x[0][0], 0.0]);
        assert_eq!(whole[N / 2], [x[N / 2][0], 0.0]);
        assert_eq!(whole[1..N / 2], x[1..N / 2]);
        let top = x
            .iter()
            .fold(0.0f32, |t, v| t.max(libm::hypotf(v[0], v[1])));
        for (k, (a, b)) in whole.iter().zip(&x).enumerate() {
            let err = libm::hypotf(a[0] - b[0], a[1] - b[1]);
            assert!(err < 1e-5 * top, "line {k}: {a:?} vs {b:?}");
        }
    }

    /// A whole-line Doppler step as an index shift of the spectrum equals the explicit re-mix
    /// of the millisecond's bins with `e^{−j2π·lines·n/N}` and a new FFT, to f32 rounding.
    #[test]
    fn an_index_shift_equals_an_explicit_remix() {
        const N: usize = 1024;
        let fft = Fft::<N>::new().unwrap();
        let x = gaussian_points::<N>(11, true);
        let mut spectrum = x;
        fft.forward(&mut spectrum);
        let mut ones = [0.0f32; N];
        pack_real_spectrum(&[[1.0f32, 0.0]; N], &mut ones);
        for lines in [-50i32, -7, -1, 0, 1, 13, 50] {
            let mut remixed = x;
            for (n, v) in remixed.iter_mut().enumerate() {
                let a = -2.0 * core::f64::consts::PI * f64::from(lines) * n as f64 / N as f64;
                let (c, s) = (libm::cos(a) as f32, libm::sin(a) as f32);
                *v = [v[0] * c - v[1] * s, v[0] * s + v[1] * c];
            }
            fft.forward(&mut remixed);
            // (the shifted product with a code of ones is the conjugated shifted spectrum)
            let mut shifted = [[0.0f32; 2]; N];
            correlate_shifted(&spectrum, &ones, lines, &mut shifted);
            let (mut err, mut top) = (0.0f32, 0.0f32);
            for (a, b) in shifted.iter().zip(remixed.iter()) {
                err = err.max(libm::hypotf(a[0] - b[0], a[1] + b[1]));
                top = top.max(libm::hypotf(b[0], b[1]));
            }
            assert!(err < 3e-6 * top, "lines {lines}: {err} of {top}");
        }
    }

    /// Room for 3 ms at 2.6 Msps.
    const SAMPLES: usize = 24_000;
    type Samples = heapless::Vec<i8, SAMPLES>;

    /// Complex samples of one satellite without data bits (PRN, amplitude LSB, Doppler Hz,
    /// code phase chips) in noise of `sigma` LSB at 2.6 Msps, rounded to i8.
    fn satellite(p: u8, a: f64, f: f64, tau: f64, sigma: f32, n: usize) -> (Samples, Samples) {
        let mut rng = SplitMix64::new(u64::from(p) + 100);
        let mut normal = StandardNormal::new();
        let prn = Prn::new(p).unwrap();
        let (mut i, mut q) = (Samples::new(), Samples::new());
        for k in 0..n.min(SAMPLES) {
            let t = k as f64 / 2.6e6;
            let chip = (tau + t * CA_CHIP_RATE_HZ * (1.0 + f / GPS_L1_HZ)) % 1023.0;
            let c = f64::from(prn.chip(chip as usize % CA_CODE_LENGTH));
            let ph = core::f64::consts::TAU * f * t;
            let x = a * c * libm::cos(ph) + f64::from(sigma * normal.sample(&mut rng));
            let y = a * c * libm::sin(ph) + f64::from(sigma * normal.sample(&mut rng));
            i.push(libm::round(x).clamp(-128.0, 127.0) as i8)
                .expect("room");
            q.push(libm::round(y).clamp(-128.0, 127.0) as i8)
                .expect("room");
        }
        (i, q)
    }

    /// The dwell's direct correlation against the FFT's: its strongest window cell times
    /// `N²` is the remix search's strongest cell in the same window to 0.1 % (f32 both),
    /// on the peak and 300 lags away from it, across the code's wrap and with the code
    /// Doppler's drift over 4 ms; on noise alone its model background is the FFT scan's
    /// measured one to 5 % (about 3 standard errors of the measured one).
    #[test]
    fn the_dwells_direct_cells_equal_the_fft_scans() {
        let config = AcquisitionConfig {
            sample_rate_hz: 2.6e6,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 5_000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 4,
            false_alarm_probability: 1e-3,
        };
        const N: usize = 1024;
        let n2 = (N * N) as f32;
        for &(p, f, tau) in &[
            (3u8, 420.0, 300.2),
            (17, -4_270.0, 0.3),
            (24, 31_830.0, 1022.6),
        ] {
            let prn = Prn::new(p).unwrap();
            let (i, q) = satellite(p, 2.0, f, tau, 8.0, config.search_samples());
            let mut engine = Acquisition::<N, 2>::new().unwrap();
            engine.prepare_code(prn);
            let power = engine.accumulate_remix(cx(&i, &q), f as f32, &config, [0.0; 2]);
            let peak_at = (0..N).fold(0, |a, l| if power[l] > power[a] { l } else { a });
            for centre in [peak_at, (peak_at + 300) % N] {
                let window = CodeWindow { centre, half: 2 };
                let fft = (0..N)
                    .filter(|&l| window.contains(l, N))
                    .fold(0.0f32, |a, l| a.max(power[l]));
                let grid = Grid {
                    first_hz: f as f32,
                    step_hz: 0.0,
                    bins: 1,
                    first_ms: 0,
                };
                let (direct, _) =
                    engine.scan_window(prn, cx(&i, &q), &grid, window, &config, [0.0; 2]);
                assert!(
                    (direct * n2 / fft - 1.0).abs() < 1e-3,
                    "PRN {p} centre {centre}: {} vs {fft}",
                    direct * n2
                );
            }
        }
        let (i, q) = satellite(5, 0.0, 0.0, 0.0, 8.0, config.samples_needed());
        let mut engine = Acquisition::<N, 2>::new().unwrap();
        let prn = Prn::new(5).unwrap();
        engine.prepare_code(prn);
        let grid = Grid::dwell(&config, 1_250.0);
        let window = CodeWindow {
            centre: 700,
            half: 2,
        };
        let (_, floor) = engine.scan(cx(&i, &q), &grid, Some(window), &config, [0.0; 2]);
        let (_, mean) = engine.scan_window(prn, cx(&i, &q), &grid, window, &config, [0.0; 2]);
        let ratio = mean * n2 / floor.mean();
        assert!((ratio - 1.0).abs() < 0.05, "{ratio}");
    }

    /// The shared-FFT scan (lanes of whole-line shifts of one spectrum per millisecond)
    /// against the search it replaced (each bin re-mixed and transformed; f32 both): the
    /// satellite's bin has its peak at the same lag with the same power to 3 % (0.13 dB:
    /// the shift mixes the integrated bins, not the samples, which differs by the bins'
    /// own smearing and aliasing), and the strongest cell is the same bin and lag, on
    /// satellites at LEO Dopplers up to 47 kHz.
    #[test]
    fn the_shared_fft_scan_equals_the_remix_search() {
        let config = AcquisitionConfig {
            sample_rate_hz: 2.6e6,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 50_000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 2,
            false_alarm_probability: 1e-3,
        };
        for &(p, f, tau) in &[
            (3u8, 420.0, 300.2),
            (17, -31_270.0, 12.7),
            (24, 46_830.0, 811.5),
        ] {
            let (i, q) = satellite(p, 2.0, f, tau, 8.0, config.search_samples());
            let mut shared = Acquisition::<1024, 4>::new().unwrap();
            shared.prepare_code(Prn::new(p).unwrap());
            let grid = Grid::search(&config, 0.0);
            let (peak, _) = shared.scan(cx(&i, &q), &grid, None, &config, [0.0; 2]);
            let mut reference = Acquisition::<1024, 1>::new().unwrap();
            reference.prepare_code(Prn::new(p).unwrap());
            let (mut best, mut best_at) = (0.0f32, (0usize, 0usize));
            // the bins around the satellite and a few far ones
            let near = libm::round((f - f64::from(grid.first_hz)) / 500.0) as usize;
            for b in [0, 57, near - 2, near - 1, near, near + 1, near + 2, 200] {
                let power =
                    reference.accumulate_remix(cx(&i, &q), grid.doppler(b), &config, [0.0; 2]);
                let (at, top) =
                    power
                        .iter()
                        .enumerate()
                        .fold((0, 0.0f32), |a, (l, &v)| if v > a.1 { (l, v) } else { a });
                let (mine, mine_at) = shared.peaks[b];
                if b == near {
                    assert_eq!(mine_at as usize, at, "PRN {p} bin {b}");
                    assert!(
                        (mine / top - 1.0).abs() < 0.03,
                        "PRN {p} bin {b}: {mine} vs {top}"
                    );
                }
                if top > best {
                    (best, best_at) = (top, (b, at));
                }
            }
            assert_eq!((peak.bin, peak.lag), best_at, "PRN {p}");
            assert!(
                (peak.power / best - 1.0).abs() < 0.03,
                "PRN {p}: {}",
                peak.power / best
            );
        }
    }

    /// Background statistics against an f64 reference, at a power scale whose squares would
    /// overflow f32 (1e20: cells of a strong, loud input): `Gamma(k)`-like cells give `k`, a
    /// repeating background (exponential cells) gives 1.
    #[test]
    fn the_background_statistics_hold_at_any_scale() {
        let mut rng = SplitMix64::new(9);
        let mut normal = StandardNormal::new();
        for (k, expected) in [(20usize, 20u16), (1, 1)] {
            let mut floor = Floor::default();
            let (mut s, mut s2, mut n) = (0.0f64, 0.0f64, 0.0f64);
            for _ in 0..8 {
                let mut power = [0.0f32; 1024];
                for p in power.iter_mut() {
                    // sum of k exponentials (|complex normal|²), mean 1, times 1e20
                    let mut v = 0.0f32;
                    for _ in 0..k {
                        let (a, b) = (normal.sample(&mut rng), normal.sample(&mut rng));
                        v += 0.5 * (a * a + b * b) / k as f32;
                    }
                    *p = v * 1e20;
                }
                floor.add_bin(&power, 0, 3);
                for &p in power.iter().skip(4).take(1024 - 7) {
                    let p = f64::from(p);
                    (s, s2, n) = (s + p, s2 + p * p, n + 1.0);
                }
            }
            let mean = s / n;
            assert!((f64::from(floor.mean()) / mean - 1.0).abs() < 1e-5);
            assert_eq!(floor.effective_ms(20), expected, "k {k}");
            let reference = mean * mean / (s2 / n - mean * mean);
            assert!(
                (reference - k as f64).abs() < 0.1 * k as f64 + 0.2,
                "{reference}"
            );
        }
    }
}
