//! Acquisition on the reference antenna: a code-phase × Doppler search with parallel code
//! phase (FFT circular correlation), fixed memory, bounded time, and a detection threshold
//! derived from a stated false-alarm probability.
//!
//! # Method
//! For each Doppler bin `f` (from `−f_max` to `+f_max` in steps of `Δf`) and each of `K`
//! milliseconds: the samples are mixed with `e^{−j2π(f_IF + f)t}` (the carrier table of the
//! correlator, integer products) and integrated-and-dumped into `N` bins per millisecond
//! (`N` a power of two ≥ 1024: 0.5 chip per bin for `N = 2048`); the `N`-point FFT of that,
//! times the conjugate spectrum of the code integrated over the same bins, inverse-transformed,
//! gives the correlation at all `N` code phases. `|·|²` is summed over the `K` ms
//! (non-coherently, so data bits do not matter), shifting each millisecond by the code Doppler
//! `m·N·f/f_L1` bins so that the code drift of LEO Dopplers does not smear the peak.
//!
//! # Detection (false-alarm threshold)
//! With noise only, each cell's `K`-ms sum divided by the mean over all cells is
//! `Gamma(K, 1/K)` distributed (a sum of `K` exponentials, cells independent because the code
//! has low autocorrelation). For a false-alarm probability `P_fa` per PRN search over
//! `M = N · (Doppler bins)` cells, the per-cell probability is `p = 1 − (1 − P_fa)^{1/M}` and
//! the threshold `t` solves `Q(K, K t) = p` (regularized upper incomplete gamma, bisection
//! bounded to 100 steps). A PRN is detected when its peak cell over the mean exceeds `t`.
//!
//! # Refinement
//! The code phase is refined by the triangle interpolation of the peak and its two code
//! neighbours, the Doppler by a parabola through the peak amplitudes of the neighbouring
//! Doppler bins.
//!
//! # Memory and time
//! `Acquisition<N>` holds four `N`-element arrays (twiddles, code spectrum, data, power) and
//! one peak per Doppler bin: 60 KiB for `N = 2048`, 30 KiB for `N = 1024` (the target's
//! choice). Per PRN: `bins · K` × (mixing of 1 ms of samples + two FFTs).

use super::fft::{Complex, Fft};

use crate::error::{Error, ErrorKind};
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ, CA_CODE_LENGTH, GPS_L1_HZ};
use crate::signal::nco::{carrier_index, CarrierNco, COS_TABLE, SIN_TABLE};

/// Most Doppler bins one search may have (±50 kHz in 250 Hz steps fits).
pub const MAX_DOPPLER_BINS: usize = 401;

/// Most milliseconds summed non-coherently.
pub const MAX_NONCOHERENT_MS: u16 = 200;

/// What to search and how.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AcquisitionConfig {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz (0 for complex baseband).
    pub intermediate_frequency_hz: f64,
    /// The search covers Dopplers in `[−doppler_max_hz, +doppler_max_hz]`, Hz (up to 50 kHz
    /// for LEO).
    pub doppler_max_hz: f32,
    /// Doppler bin spacing, Hz (500 Hz loses at most 0.9 dB with 1 ms coherent sums).
    pub doppler_step_hz: f32,
    /// Milliseconds summed non-coherently, `K`.
    pub noncoherent_ms: u16,
    /// Probability of a false detection per PRN search (noise only).
    pub false_alarm_probability: f32,
}

impl AcquisitionConfig {
    /// Number of Doppler bins.
    pub fn doppler_bins(&self) -> usize {
        let half = libm::floorf(self.doppler_max_hz / self.doppler_step_hz);
        if half.is_finite() && half >= 0.0 {
            2 * half as usize + 1
        } else {
            0
        }
    }

    /// Samples the search reads: `K` ms (rounded up) plus one.
    pub fn samples_needed(&self) -> usize {
        libm::ceil(f64::from(self.noncoherent_ms) * self.sample_rate_hz * 1e-3) as usize + 1
    }

    fn validate(&self) -> Result<(), AcquisitionError> {
        let finite = self.sample_rate_hz.is_finite()
            && self.intermediate_frequency_hz.is_finite()
            && self.doppler_max_hz.is_finite()
            && self.doppler_step_hz.is_finite()
            && self.false_alarm_probability.is_finite();
        if !finite {
            return Err(AcquisitionError::NonFinite);
        }
        let fs = self.sample_rate_hz;
        let front_end_ok =
            (CA_CHIP_RATE_HZ..=64e6).contains(&fs) && self.intermediate_frequency_hz.abs() < fs;
        let doppler_ok = self.doppler_step_hz >= 10.0 && self.doppler_max_hz >= 0.0;
        if !front_end_ok
            || !doppler_ok
            || self.doppler_bins() == 0
            || self.doppler_bins() > MAX_DOPPLER_BINS
            || self.noncoherent_ms == 0
            || self.noncoherent_ms > MAX_NONCOHERENT_MS
            || !(self.false_alarm_probability > 0.0 && self.false_alarm_probability < 0.5)
        {
            return Err(AcquisitionError::InvalidConfig);
        }
        Ok(())
    }
}

/// The outcome of one PRN's search.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SearchResult {
    /// The PRN searched.
    pub prn: Prn,
    /// Whether the peak exceeded the threshold.
    pub detected: bool,
    /// Peak cell over the mean cell (the test statistic).
    pub metric: f32,
    /// The detection threshold for the configured false-alarm probability.
    pub threshold: f32,
    /// Doppler of the peak, refined, Hz.
    pub doppler_hz: f32,
    /// Code phase of the received code at the first sample searched, chips in `[0, 1023)`.
    pub code_phase_chips: f32,
    /// Receiver sample index of the first sample searched.
    pub first_sample: u64,
}

/// The acquisition engine with its fixed workspace (`N` bins per millisecond).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Acquisition<const N: usize> {
    fft: Fft<N>,
    code: [Complex; N],
    data: [Complex; N],
    power: [f32; N],
    peaks: [(f32, u32); MAX_DOPPLER_BINS],
}

impl<const N: usize> Acquisition<N> {
    /// A new engine.
    ///
    /// # Errors
    /// [`AcquisitionError::InvalidConfig`] unless `N` is a power of two in 1024–8192.
    pub fn new() -> Result<Self, AcquisitionError> {
        if !(1024..=8192).contains(&N) {
            return Err(AcquisitionError::InvalidConfig);
        }
        let fft = Fft::new().ok_or(AcquisitionError::InvalidConfig)?;
        Ok(Self {
            fft,
            code: [[0.0; 2]; N],
            data: [[0.0; 2]; N],
            power: [0.0; N],
            peaks: [(0.0, 0); MAX_DOPPLER_BINS],
        })
    }

    /// Searches `prn` in the reference antenna's samples (`q = None` for real samples).
    /// `first_sample` is the receiver index of `i[0]`.
    ///
    /// Bounded: `bins · K` iterations, each one millisecond of samples and two `N`-point FFTs.
    ///
    /// # Errors
    /// [`AcquisitionError::InvalidConfig`], [`AcquisitionError::NonFinite`],
    /// [`AcquisitionError::NotEnoughSamples`] (fewer than
    /// [`AcquisitionConfig::samples_needed`]), [`AcquisitionError::LengthMismatch`] (`q`
    /// shorter than `i`).
    pub fn search(
        &mut self,
        prn: Prn,
        i: &[i8],
        q: Option<&[i8]>,
        first_sample: u64,
        config: &AcquisitionConfig,
    ) -> Result<SearchResult, AcquisitionError> {
        config.validate()?;
        let needed = config.samples_needed();
        if i.len() < needed {
            return Err(AcquisitionError::NotEnoughSamples);
        }
        if let Some(q) = q {
            if q.len() < i.len() {
                return Err(AcquisitionError::LengthMismatch);
            }
        }
        let bins = config.doppler_bins();
        let half = (bins / 2) as i32;
        let threshold = detection_threshold(
            config.noncoherent_ms,
            (N * bins) as f64,
            f64::from(config.false_alarm_probability),
        );
        self.prepare_code(prn);
        let mut total = 0.0f64;
        let mut best = (0.0f32, 0usize, 0usize); // (power, doppler bin, code bin)
        let mut best_neighbours = [0.0f32; 2];
        for b in 0..bins {
            let doppler = (b as i32 - half) as f32 * config.doppler_step_hz;
            self.power = [0.0; N];
            for m in 0..usize::from(config.noncoherent_ms) {
                self.decimate(i, q, m, doppler, config);
                self.fft.transform(&mut self.data, false);
                for (d, c) in self.data.iter_mut().zip(self.code.iter()) {
                    // X · conj(C)
                    *d = [d[0] * c[0] + d[1] * c[1], d[1] * c[0] - d[0] * c[1]];
                }
                self.fft.transform(&mut self.data, true);
                // Code Doppler: ms m's lag is shifted by −m·N·f/f_L1 bins.
                let drift =
                    libm::round(m as f64 * N as f64 * f64::from(doppler) / GPS_L1_HZ) as i64;
                let shift = drift.rem_euclid(N as i64) as usize;
                for (l, p) in self.power.iter_mut().enumerate() {
                    let d = self.data[(l + N - shift) & (N - 1)];
                    *p += d[0] * d[0] + d[1] * d[1];
                }
            }
            let (mut peak, mut at) = (0.0f32, 0usize);
            for (l, &p) in self.power.iter().enumerate() {
                total += f64::from(p);
                if p > peak {
                    peak = p;
                    at = l;
                }
            }
            if let Some(slot) = self.peaks.get_mut(b) {
                *slot = (peak, at as u32);
            }
            if peak > best.0 {
                best = (peak, b, at);
                best_neighbours = [
                    self.power[(at + N - 1) & (N - 1)],
                    self.power[(at + 1) & (N - 1)],
                ];
            }
        }
        let mean = (total / (N * bins) as f64) as f32;
        let metric = if mean > 0.0 { best.0 / mean } else { 0.0 };
        // Code phase: triangle interpolation on amplitudes; lag ℓ means phase (N − ℓ)·1023/N.
        let (a0, am, ap) = (
            libm::sqrtf(best.0),
            libm::sqrtf(best_neighbours[0]),
            libm::sqrtf(best_neighbours[1]),
        );
        let denom = 2.0 * (a0 - am.min(ap));
        let delta = if denom > 0.0 {
            ((ap - am) / denom).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        let lag = best.2 as f32 + delta;
        let mut code_phase = (N as f32 - lag) * (CA_CODE_LENGTH as f32 / N as f32);
        code_phase -= libm::floorf(code_phase / CA_CODE_LENGTH as f32) * CA_CODE_LENGTH as f32;
        // Doppler: parabola through the neighbouring bins' peak amplitudes.
        let amp = |b: usize| self.peaks.get(b).map_or(0.0, |p| libm::sqrtf(p.0));
        let bd = best.1;
        let (fm, f0, fp) = (
            if bd > 0 { amp(bd - 1) } else { 0.0 },
            amp(bd),
            if bd + 1 < bins { amp(bd + 1) } else { 0.0 },
        );
        let curv = 2.0 * f0 - fm - fp;
        let df = if curv > 0.0 {
            (0.5 * (fp - fm) / curv).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        let doppler = ((bd as i32 - half) as f32 + df) * config.doppler_step_hz;
        Ok(SearchResult {
            prn,
            detected: metric > threshold,
            metric,
            threshold,
            doppler_hz: doppler,
            code_phase_chips: code_phase,
            first_sample,
        })
    }

    /// The code of `prn` integrated over the `N` bins of one code period, transformed.
    fn prepare_code(&mut self, prn: Prn) {
        const SUB: usize = 8;
        for (b, c) in self.code.iter_mut().enumerate() {
            let mut s = 0i32;
            for k in 0..SUB {
                let chip = ((b * SUB + k) * CA_CODE_LENGTH) / (N * SUB);
                s += i32::from(prn.chip(chip));
            }
            *c = [s as f32 / SUB as f32, 0.0];
        }
        self.fft.transform(&mut self.code, false);
    }

    /// Mixes millisecond `m` of the samples with the Doppler bin's carrier and integrates it
    /// into the `N` bins of `self.data`.
    fn decimate(
        &mut self,
        i: &[i8],
        q: Option<&[i8]>,
        m: usize,
        doppler: f32,
        config: &AcquisitionConfig,
    ) {
        self.data = [[0.0; 2]; N];
        let fs = config.sample_rate_hz;
        let start = libm::ceil(m as f64 * fs * 1e-3) as usize;
        let end = libm::ceil((m + 1) as f64 * fs * 1e-3) as usize;
        let step = CarrierNco::step_for(config.intermediate_frequency_hz + f64::from(doppler), fs);
        // Bin of sample k: floor((k/f_s − m·1 ms) · N · 1000), in 32.32 fixed point.
        let bin_step = libm::round(N as f64 * 1000.0 / fs * 4_294_967_296.0) as u64;
        let t0 = (start as f64 / fs - m as f64 * 1e-3) * N as f64 * 1000.0;
        let mut bin_acc = libm::round(t0 * 4_294_967_296.0) as u64;
        let mut phase = 0u32;
        let end = end.min(i.len());
        for k in start..end {
            let x = i32::from(i.get(k).copied().unwrap_or(0));
            let y = q.and_then(|q| q.get(k)).map_or(0, |v| i32::from(*v));
            let idx = carrier_index(phase);
            let (c, s) = (i32::from(COS_TABLE[idx]), i32::from(SIN_TABLE[idx]));
            let bin = ((bin_acc >> 32) as usize) & (N - 1);
            let d = &mut self.data[bin];
            d[0] += (x * c + y * s) as f32;
            d[1] += (y * c - x * s) as f32;
            phase = phase.wrapping_add(step);
            bin_acc += bin_step;
        }
    }
}

/// The threshold `t` on peak/mean for a false-alarm probability `p_fa` over `cells` cells with
/// `k` ms summed: solves `Q(k, k t) = 1 − (1 − p_fa)^{1/cells}` by bisection (100 steps).
pub fn detection_threshold(k: u16, cells: f64, p_fa: f64) -> f32 {
    let k = f64::from(k.max(1));
    // Per-cell probability, in logs for accuracy: ln p = ln(−expm1(ln(1−P)/M)).
    let ln_p_cell = libm::log(-libm::expm1(libm::log1p(-p_fa) / cells.max(1.0)));
    let (mut lo, mut hi) = (1.0f64, 200.0f64);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if ln_gamma_survival(k, k * mid) > ln_p_cell {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)) as f32
}

/// `ln Q(k, x) = ln(e^{−x} Σ_{i<k} xⁱ/i!)` for integer `k` (log-sum-exp, `k` ≤ 200 terms).
fn ln_gamma_survival(k: f64, x: f64) -> f64 {
    let n = k as usize;
    let mut max_term = f64::NEG_INFINITY;
    let mut ln_term = 0.0f64; // ln(x^0/0!)
    let mut terms = [0.0f64; MAX_NONCOHERENT_MS as usize];
    for (i, t) in terms.iter_mut().enumerate().take(n) {
        if i > 0 {
            ln_term += libm::log(x) - libm::log(i as f64);
        }
        *t = ln_term;
        max_term = max_term.max(ln_term);
    }
    let mut sum = 0.0;
    for t in terms.iter().take(n) {
        sum += libm::exp(t - max_term);
    }
    -x + max_term + libm::log(sum)
}

/// Errors of acquisition ([`crate::tracking::acquisition`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AcquisitionError {
    /// A configuration value was NaN or infinite.
    #[error("non-finite acquisition configuration")]
    NonFinite,
    /// The configuration is out of range (sample rate outside 1.023–64 MHz, IF beyond the
    /// sample rate, Doppler step below 10 Hz, more Doppler bins than the engine holds, zero or
    /// too many milliseconds, a false-alarm probability outside (0, 0.5)), or the engine's
    /// FFT size is not a power of two in 1024–8192.
    #[error("acquisition configuration out of range")]
    InvalidConfig,
    /// Fewer samples than the configured number of milliseconds needs.
    #[error("fewer samples than the search needs")]
    NotEnoughSamples,
    /// The quadrature samples are fewer than the in-phase samples.
    #[error("quadrature samples shorter than in-phase samples")]
    LengthMismatch,
}

impl Error for AcquisitionError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            _ => ErrorKind::InvalidInput,
        }
    }
}
