//! Acquisition on the reference antenna: a code-phase × Doppler search with parallel code
//! phase (FFT circular correlation), fixed memory, bounded time, and a detection test that
//! holds its false-alarm probability on any background: thermal noise, noise-free simulator
//! output, strong signals, saturated, constant or tone-jammed inputs.
//!
//! # Method
//! The mean of the samples searched is removed first (a DC offset, a constant or saturated
//! input would otherwise correlate with every code at the Doppler bins near multiples of
//! 1 kHz). For each Doppler bin `f` (from `−f_max` to `+f_max` in steps of `Δf`, about zero, or
//! about the predicted Doppler for a warm start: [`Acquisition::search_report_near`]) and each of
//! `K` milliseconds: the samples are mixed with `e^{−j2π(f_IF + f)t}` (the carrier table of
//! the correlator) and integrated-and-dumped into `N` bins per millisecond (`N` a power of two
//! ≥ 1024: 0.5 chip per bin for `N = 2048`); the `N`-point FFT of that, with the lines above
//! [`EXCISION_FACTOR`] times the background line power removed together with their leakage
//! (a continuous-wave interferer: frequency-domain excision), times the conjugate spectrum of the code integrated over the same bins,
//! inverse-transformed, gives the correlation at all `N` code phases. `|·|²` is summed over the `K` ms (non-coherently, so
//! data bits do not matter), shifting each millisecond by the code Doppler `m·N·f/f_L1` bins
//! so that the code drift of LEO Dopplers does not smear the peak.
//!
//! # Detection: a threshold from the search's own background
//! With thermal noise only, each cell's `K`-ms sum over the background mean is `Gamma(K, 1/K)`
//! distributed (a sum of `K` exponentials). Other backgrounds are not: without thermal noise
//! the cells hold the other satellites' cross-correlations, which repeat every millisecond
//! (the sum over `K` ms does not average them), and a strong satellite, a tone or a DC offset
//! put structure of their own into the cells. The test therefore measures the background
//! from the search itself: in every Doppler bin the cells more than [`FLOOR_GUARD_CHIPS`]
//! from that bin's peak give the mean `μ` and the variance `σ²` of the background, and
//! `K_eff = ⌊μ²/σ²⌋` (clamped to `1..=K`) is the number of independent milliseconds the
//! background behaves as (`K` on thermal noise, where `σ² = μ²/K`; 1 when the cells repeat
//! every millisecond). For a false-alarm probability `P_fa` per PRN search over
//! `M = N · (Doppler bins)` cells the per-cell probability is `p = 1 − (1 − P_fa)^{1/M}` and
//! the threshold `t` solves `Q(K_eff, K_eff t) = p` (regularized upper incomplete gamma,
//! bisection bounded to 100 steps). A PRN is a *candidate* when its peak over `μ` exceeds `t`.
//! On thermal noise `K_eff = K` and the test is the classic one (same detection and false-alarm
//! probabilities).
//!
//! # Verification dwell
//! A candidate is re-tested on the next `K` milliseconds (fresh data): three Doppler bins
//! (the refined Doppler and ±`Δf/2`), and the peak sought within
//! [`VERIFICATION_CODE_WINDOW_CHIPS`] of the code phase the candidate predicts there, against
//! the same kind of threshold for [`VERIFICATION_FALSE_ALARM`] over those few cells. A PRN is
//! *detected* only when its candidate passes the dwell ([`AcquisitionConfig::samples_needed`]
//! counts both periods; with fewer samples a candidate is reported but not detected).
//!
//! # Cross-correlation test
//! The other satellites' cross-correlation repeats every millisecond and passes the dwell; it
//! is tested against the stronger satellites already detected or tracked
//! ([`Acquisition::cross_check`]): each signal's power is measured on the samples searched by
//! a direct correlation at its code phase and Doppler, and the candidate is rejected when its
//! power is explained by the stronger ones' cross-correlation at its code lag and Doppler
//! offset ([`super::xcorr`]; the strong cases are Doppler differences near multiples of 1 kHz).
//!
//! # Second look, with the known satellites cancelled
//! A satellite weaker than the others by 10–15 dB can be masked by their cross-correlation:
//! its search's background rises and repeats (the threshold rises), or its peak sits where
//! a stronger code cross-correlates and the test above explains it away.
//! [`Acquisition::search_report_cancelling`] searches again with the known signals
//! subtracted from the samples (their code phase and Doppler refined, their phasor measured
//! every millisecond), and [`Acquisition::cancellation_check`] tells a satellite
//! (it keeps its power with them cancelled) from their cross-correlation (it loses it).
//!
//! # Refinement
//! The code phase is refined by the triangle interpolation of the peak and its two code
//! neighbours, the Doppler by a parabola through the peak amplitudes of the neighbouring
//! Doppler bins.
//!
//! # Samples
//! A search reads [`SearchSamples`]: the reference antenna's samples decoded to `i8`, or
//! the bit planes of a 1- or 2-bit front end read as they are (the same values, the same
//! report; a microcontroller keeps 13 ms of 2-bit complex planes in 15 KiB instead of 61 KiB
//! of `i8`).
//!
//! # Memory and time
//! `Acquisition<N>` holds four `N`-element arrays (twiddles, code spectrum, data, power) and
//! one peak per Doppler bin: 60 KiB for `N = 2048`, 30 KiB for `N = 1024` (the target's
//! choice). Per PRN: `bins · K` × (mixing of 1 ms of samples + two FFTs); a candidate's dwell
//! adds `3 · K` of those; the cross-correlation test `K` ms of direct correlation per signal.

mod cancel;
mod check;
mod input;
mod scan;
mod tone;

use super::fft::{Complex, Fft};
use crate::error::{Error, ErrorKind};
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ};

pub use cancel::{MAX_CANCELLED, REFINE_MS, REFINE_STEP_CHIPS};
pub use check::{CancellationCheck, CrossCheck, KnownSignal, CANCELLATION_KEEP_FRACTION};
pub use input::SearchSamples;
pub use scan::EXCISION_FACTOR;
pub use tone::TONE_FACTOR;

/// Most Doppler bins one search may have (±50 kHz in 250 Hz steps fits).
pub const MAX_DOPPLER_BINS: usize = 401;

/// Most milliseconds summed non-coherently.
pub const MAX_NONCOHERENT_MS: u16 = 200;

/// Code distance from a Doppler bin's peak within which cells are left out of the background
/// statistics, chips (the correlation triangle is ±1 chip wide).
pub const FLOOR_GUARD_CHIPS: f32 = 1.5;

/// Largest predicted Doppler a search may be centred on
/// ([`Acquisition::search_report_near`]), Hz: a LEO satellite's Doppler stays within
/// ±45 kHz, its oscillator's offset adds a few kHz.
pub const MAX_DOPPLER_CENTRE_HZ: f32 = 60_000.0;

/// False-alarm probability of the verification dwell over its cells.
pub const VERIFICATION_FALSE_ALARM: f64 = 1e-3;

/// Half-width of the code window the verification dwell searches around the predicted code
/// phase, chips.
pub const VERIFICATION_CODE_WINDOW_CHIPS: f32 = 1.0;

/// A candidate is another satellite's cross-correlation when its power is at most this
/// times the predicted cross-correlation power (3 dB).
pub const CROSS_CORRELATION_MARGIN: f32 = 2.0;

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
    /// Milliseconds summed non-coherently, `K` (the search, and again the verification
    /// dwell).
    pub noncoherent_ms: u16,
    /// Probability of a false detection per PRN search, on any background.
    pub false_alarm_probability: f32,
}

impl AcquisitionConfig {
    /// Number of Doppler bins: `2 ⌊doppler_max_hz / doppler_step_hz⌋ + 1`, saturating at
    /// `usize::MAX` for a span no search could cover (validation then refuses it); 0 for a
    /// non-finite or negative ratio.
    pub fn doppler_bins(&self) -> usize {
        let half = libm::floorf(self.doppler_max_hz / self.doppler_step_hz);
        if half.is_finite() && half >= 0.0 {
            // (the cast saturates; so do the sums)
            (half as usize).saturating_mul(2).saturating_add(1)
        } else {
            0
        }
    }

    /// Samples a search with its verification dwell reads: `2K` ms (rounded up) plus one;
    /// saturating at `usize::MAX` for a sample rate no buffer could hold (validation then
    /// refuses it).
    pub fn samples_needed(&self) -> usize {
        self.samples_for_ms(2 * u32::from(self.noncoherent_ms))
    }

    /// Samples the search alone reads (no verification dwell: candidates are not detected):
    /// `K` ms (rounded up) plus one; saturating as [`Self::samples_needed`].
    pub fn search_samples(&self) -> usize {
        self.samples_for_ms(u32::from(self.noncoherent_ms))
    }

    fn samples_for_ms(&self, ms: u32) -> usize {
        // (the cast saturates, NaN to 0; so does the sum)
        (libm::ceil(f64::from(ms) * self.sample_rate_hz * 1e-3) as usize).saturating_add(1)
    }

    /// First sample of millisecond `m` of the searched samples.
    fn ms_start(&self, m: usize) -> usize {
        libm::ceil(m as f64 * self.sample_rate_hz * 1e-3) as usize
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
    /// Whether the peak exceeded the threshold and passed the verification dwell.
    pub detected: bool,
    /// Peak cell over the background's mean cell (the test statistic).
    pub metric: f32,
    /// The detection threshold for the configured false-alarm probability on this search's
    /// background.
    pub threshold: f32,
    /// Doppler of the peak, refined, Hz.
    pub doppler_hz: f32,
    /// Code phase of the received code at the first sample searched, chips in `[0, 1023)`.
    pub code_phase_chips: f32,
    /// Receiver sample index of the first sample searched.
    pub first_sample: u64,
}

/// What the verification dwell concluded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verification {
    /// No candidate: nothing to verify.
    NotTested,
    /// A candidate, but the samples end before the dwell's (not detected).
    NoSamples,
    /// The candidate's peak was found again on fresh data.
    Passed,
    /// It was not (not detected).
    Failed,
}

/// A search with the figures of its background and its verification.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SearchReport {
    /// The result ([`Acquisition::search`]'s).
    pub result: SearchResult,
    /// The peak exceeded the threshold (before the verification).
    pub candidate: bool,
    /// Milliseconds the background behaves as independent (`K` on thermal noise, 1 when it
    /// repeats every millisecond).
    pub effective_ms: u16,
    /// Mean background cell, engine units (cells away from each Doppler bin's peak).
    pub noise_floor: f32,
    /// The verification dwell.
    pub verification: Verification,
    /// The dwell's peak over its background (0 when not run).
    pub verification_metric: f32,
    /// The dwell's threshold (0 when not run).
    pub verification_threshold: f32,
    /// Interference was found in these samples (continuous-wave tones cancelled): a
    /// background that is not thermal may owe it to that rather than to other satellites.
    pub interference: bool,
}

/// Doppler bins that share one mix and forward FFT of each millisecond by default (the lanes
/// of [`Acquisition`]): 2 keep the engine's memory at `36·N` bytes plus the peaks (40 KB
/// for `N = 1024`, what one lane took before the code's spectrum was packed into half);
/// each further lane adds `4·N` bytes and saves most of a mix and an FFT per bin and
/// millisecond (the flight computer's budget uses 4, the host 8).
pub const DEFAULT_LANES: usize = 2;

/// The acquisition engine with its fixed workspace (`N` bins per millisecond; `L` lanes:
/// Doppler bins of one sub-bin offset searched together from one FFT of each millisecond,
/// `4·N` bytes each).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Acquisition<const N: usize, const L: usize = DEFAULT_LANES> {
    fft: Fft<N>,
    /// The FFT's tables are built ([`Acquisition::build`]).
    built: bool,
    /// The code's spectrum, packed (a real sequence's: half of it holds it all).
    code: [f32; N],
    data: [Complex; N],
    /// The spectrum product of one bin, then its correlation.
    work: [Complex; N],
    /// The non-coherent sums of the chunk's bins.
    lanes: [[f32; N]; L],
    /// The last two thresholds computed, `(k, cells, p_fa, threshold)` (`k` 0: empty): the
    /// searches of a start share them (f64 is software on the target).
    thresholds: [(u16, f64, f64, f32); 2],
    peaks: [(f32, u32); MAX_DOPPLER_BINS],
    /// Background line power of the samples' spectrum (interference excision; 0: none).
    level: f32,
    /// Tones cancelled from these samples, the first `tone_count`.
    tones: [tone::Tone; tone::MAX_TONES],
    tone_count: usize,
    /// Known signals cancelled from these samples, the first `cancelled_count`.
    cancelled: [cancel::Cancelled; MAX_CANCELLED],
    cancelled_count: usize,
}

impl<const N: usize, const L: usize> Acquisition<N, L> {
    /// A new engine.
    ///
    /// # Errors
    /// [`AcquisitionError::InvalidConfig`] unless `N` is a power of two in 1024–8192 and `L`
    /// in 1–64.
    pub fn new() -> Result<Self, AcquisitionError> {
        let mut engine = Self::blank();
        engine.build()?;
        Ok(engine)
    }

    /// An engine whose FFT tables are not built yet: every search returns
    /// [`AcquisitionError::NotBuilt`] until [`Acquisition::build`]. `const` and all zeros, so
    /// that it is made where it stays (a `static`, or a local that is never moved) and built
    /// there: [`Acquisition::new`] returns the engine by value, which can leave copies of its
    /// `(34 + 4·L)·N` bytes in the caller's frame on a microcontroller's stack.
    #[inline(never)]
    pub const fn blank() -> Self {
        Self {
            fft: Fft::blank(),
            built: false,
            code: [0.0; N],
            data: [[0.0; 2]; N],
            work: [[0.0; 2]; N],
            lanes: [[0.0; N]; L],
            thresholds: [(0, 0.0, 0.0, 0.0); 2],
            peaks: [(0.0, 0); MAX_DOPPLER_BINS],
            level: 0.0,
            tones: [tone::Tone::NONE; tone::MAX_TONES],
            tone_count: 0,
            cancelled: [cancel::Cancelled::NONE; MAX_CANCELLED],
            cancelled_count: 0,
        }
    }

    /// Builds the engine's FFT tables in place (a [`Acquisition::blank`] engine; building
    /// again changes nothing).
    ///
    /// # Errors
    /// [`AcquisitionError::InvalidConfig`] unless `N` is a power of two in 1024–8192 and `L`
    /// in 1–64 (the engine stays unbuilt).
    pub fn build(&mut self) -> Result<(), AcquisitionError> {
        Self::check_size()?;
        if self.built {
            return Ok(());
        }
        if !self.fft.build() {
            return Err(AcquisitionError::InvalidConfig);
        }
        self.built = true;
        Ok(())
    }

    /// Whether an engine of this size can be built, without building one.
    ///
    /// # Errors
    /// [`AcquisitionError::InvalidConfig`] unless `N` is a power of two in 1024–8192 and `L`
    /// in 1–64.
    pub fn check_size() -> Result<(), AcquisitionError> {
        if (1024..=8192).contains(&N) && N.is_power_of_two() && (1..=64).contains(&L) {
            Ok(())
        } else {
            Err(AcquisitionError::InvalidConfig)
        }
    }

    /// [`AcquisitionError::NotBuilt`] for a blank engine.
    fn check_built(&self) -> Result<(), AcquisitionError> {
        if self.built {
            Ok(())
        } else {
            Err(AcquisitionError::NotBuilt)
        }
    }

    /// Searches `prn` in the reference antenna's decoded samples `i` (and `q`; `None` for
    /// real samples) and verifies a candidate on the samples after the search's (see the
    /// module documentation). `first_sample` is the receiver index of `i[0]`. The search on
    /// bit planes, and with the search's figures: [`Acquisition::search_report`].
    ///
    /// Bounded: `(bins + 3) · K` iterations, each one millisecond of samples and two
    /// `N`-point FFTs.
    ///
    /// # Errors
    /// [`AcquisitionError::InvalidConfig`], [`AcquisitionError::NonFinite`],
    /// [`AcquisitionError::NotEnoughSamples`] (fewer than
    /// [`AcquisitionConfig::search_samples`]; between that and
    /// [`AcquisitionConfig::samples_needed`] nothing is detected),
    /// [`AcquisitionError::LengthMismatch`] (`q` shorter than `i`),
    /// [`AcquisitionError::NotBuilt`] (a [`Acquisition::blank`] engine not built).
    pub fn search(
        &mut self,
        prn: Prn,
        i: &[i8],
        q: Option<&[i8]>,
        first_sample: u64,
        config: &AcquisitionConfig,
    ) -> Result<SearchResult, AcquisitionError> {
        let samples = SearchSamples::decoded(i, q)?;
        self.search_report(prn, samples, first_sample, config)
            .map(|r| r.result)
    }

    /// [`detection_threshold`], remembered for the last two arguments.
    fn threshold(&mut self, k: u16, cells: f64, p_fa: f64) -> f32 {
        let key = |e: &(u16, f64, f64, f32)| e.0 == k && e.1 == cells && e.2 == p_fa;
        if let Some(e) = self.thresholds.iter().find(|e| key(e)) {
            return e.3;
        }
        let t = detection_threshold(k, cells, p_fa);
        self.thresholds = [(k, cells, p_fa, t), self.thresholds[0]];
        t
    }

    /// [`Acquisition::search`] on `samples` (decoded or bit planes; the first is receiver
    /// sample `first_sample`), with the background's figures and the verification's outcome.
    ///
    /// # Errors
    /// As [`Acquisition::search`] ([`AcquisitionError::LengthMismatch`] comes from
    /// [`SearchSamples::decoded`]).
    pub fn search_report(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        first_sample: u64,
        config: &AcquisitionConfig,
    ) -> Result<SearchReport, AcquisitionError> {
        self.search_report_cancelling(prn, samples, first_sample, config, &[])
    }

    /// [`Acquisition::search_report`] on the samples with the `known` signals (detected or
    /// tracked on these samples; entries of `prn` skipped, at most [`MAX_CANCELLED`], the
    /// first ones) cancelled from every millisecond of the search and of its dwell (see
    /// the module documentation): the second look at a PRN that stronger satellites masked,
    /// their cross-correlation gone from the background and from its cells.
    ///
    /// Bounded: as [`Acquisition::search`], each millisecond with one more pass over its
    /// samples per signal cancelled, plus `9 + 1` passes over [`REFINE_MS`] ms per signal
    /// to refine it.
    ///
    /// # Errors
    /// As [`Acquisition::search`], and [`AcquisitionError::NonFinite`] for a non-finite
    /// known signal.
    pub fn search_report_cancelling(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        first_sample: u64,
        config: &AcquisitionConfig,
        known: &[KnownSignal],
    ) -> Result<SearchReport, AcquisitionError> {
        self.search_report_cancelling_near(prn, samples, first_sample, config, known, 0.0)
    }

    /// [`Acquisition::search_report`] over `±doppler_max_hz` about `predicted_doppler_hz`
    /// instead of about zero: a warm start's search, the Doppler predicted from the almanac,
    /// time and orbit (its error, the oscillator's offset included, within the span). The
    /// threshold counts the same cells, so the false-alarm probability is unchanged.
    ///
    /// # Errors
    /// As [`Acquisition::search`], and [`AcquisitionError::NonFinite`] for a non-finite
    /// prediction, [`AcquisitionError::InvalidConfig`] for one beyond
    /// [`MAX_DOPPLER_CENTRE_HZ`].
    pub fn search_report_near(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        first_sample: u64,
        config: &AcquisitionConfig,
        predicted_doppler_hz: f32,
    ) -> Result<SearchReport, AcquisitionError> {
        self.search_report_cancelling_near(
            prn,
            samples,
            first_sample,
            config,
            &[],
            predicted_doppler_hz,
        )
    }

    /// [`Acquisition::search_report_cancelling`] about `predicted_doppler_hz`
    /// ([`Acquisition::search_report_near`]).
    ///
    /// # Errors
    /// As [`Acquisition::search_report_cancelling`] and [`Acquisition::search_report_near`].
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn search_report_cancelling_near(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        first_sample: u64,
        config: &AcquisitionConfig,
        known: &[KnownSignal],
        predicted_doppler_hz: f32,
    ) -> Result<SearchReport, AcquisitionError> {
        self.check_built()?;
        check_inputs(samples, config)?;
        check_centre(predicted_doppler_hz)?;
        check_known(known)?;
        let dc = samples.mean(config.samples_needed());
        self.prepare_interference(samples, config, dc);
        self.set_cancellation(prn, known, samples, config, dc);
        self.prepare_code(prn);
        let grid = scan::Grid::search(config, predicted_doppler_hz);
        let (peak, floor) = self.scan(samples, &grid, None, config, dc);
        let k = config.noncoherent_ms;
        let effective_ms = floor.effective_ms(k);
        let noise_floor = floor.mean();
        let cells = N as f64 * config.doppler_bins() as f64; // (exact below 2⁵³)
        let threshold = self.threshold(
            effective_ms,
            cells,
            f64::from(config.false_alarm_probability),
        );
        let metric = if noise_floor > 0.0 {
            peak.power / noise_floor
        } else {
            0.0
        };
        let (doppler_hz, code_phase_chips) = self.refine(&peak, &grid);
        let candidate = metric > threshold;
        let dwell = if candidate {
            self.verify(
                prn,
                samples,
                doppler_hz,
                code_phase_chips,
                effective_ms,
                config,
                dc,
            )
        } else {
            scan::Dwell::not_tested()
        };
        Ok(SearchReport {
            result: SearchResult {
                prn,
                detected: candidate && dwell.verification == Verification::Passed,
                metric,
                threshold,
                doppler_hz,
                code_phase_chips,
                first_sample,
            },
            candidate,
            effective_ms,
            noise_floor,
            verification: dwell.verification,
            verification_metric: dwell.metric,
            verification_threshold: dwell.threshold,
            interference: self.tone_count > 0,
        })
    }
}

/// Checks the configuration and the samples (at least the search's).
fn check_inputs(
    samples: SearchSamples<'_>,
    config: &AcquisitionConfig,
) -> Result<(), AcquisitionError> {
    config.validate()?;
    if samples.len() < config.search_samples() {
        return Err(AcquisitionError::NotEnoughSamples);
    }
    Ok(())
}

/// Refuses a non-finite Doppler centre, or one beyond [`MAX_DOPPLER_CENTRE_HZ`].
fn check_centre(centre_hz: f32) -> Result<(), AcquisitionError> {
    if !centre_hz.is_finite() {
        Err(AcquisitionError::NonFinite)
    } else if centre_hz.abs() > MAX_DOPPLER_CENTRE_HZ {
        Err(AcquisitionError::InvalidConfig)
    } else {
        Ok(())
    }
}

/// Refuses known signals with a non-finite Doppler or code phase.
fn check_known(known: &[KnownSignal]) -> Result<(), AcquisitionError> {
    if known
        .iter()
        .all(|k| k.doppler_hz.is_finite() && k.code_phase_chips.is_finite())
    {
        Ok(())
    } else {
        Err(AcquisitionError::NonFinite)
    }
}

/// The threshold `t` on peak/mean for a false-alarm probability `p_fa` over `cells` cells with
/// `k` independent ms summed: solves `Q(k, k t) = 1 − (1 − p_fa)^{1/cells}` by bisection
/// (100 steps).
#[cfg_attr(feature = "optimize-cold", optimize(size))]
pub fn detection_threshold(k: u16, cells: f64, p_fa: f64) -> f32 {
    let k = f64::from(k.clamp(1, MAX_NONCOHERENT_MS));
    // Per-cell probability, in logs for accuracy: ln p = ln(−expm1(ln(1−P)/M)).
    let ln_p_cell = libm::log(-libm::expm1(libm::log1p(-p_fa) / cells.max(1.0)));
    let (mut lo, mut hi) = (1.0f64, 200.0f64);
    let n = k as usize;
    let ln_gamma_k = ln_factorial_below(n);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if ln_gamma_survival(n, k * mid, ln_gamma_k) > ln_p_cell {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)) as f32
}

/// `ln Q(k, x) = ln(e^{−x} Σ_{i<k} xⁱ/i!)` for integer `k` ≥ 1 and `x` > 0, with
/// `ln_gamma_k = ln (k − 1)!`: the sum factored by its last term, `x^{k−1}/(k−1)!`, and
/// summed backwards (`1 + (k−1)/x + (k−1)(k−2)/x² + …`; every ratio ≤ 1 for `x ≥ k − 1`,
/// where the threshold's bisection works): one logarithm of `x` and one of the sum per
/// evaluation (the target has no double-precision unit: every f64 operation is software).
fn ln_gamma_survival(k: usize, x: f64, ln_gamma_k: f64) -> f64 {
    let (mut ratio, mut sum) = (1.0f64, 1.0f64);
    for i in (1..k).rev() {
        ratio *= i as f64 / x;
        sum += ratio;
    }
    if k <= 1 {
        return -x;
    }
    -x + (k - 1) as f64 * libm::log(x) - ln_gamma_k + libm::log(sum)
}

/// `ln (k − 1)!`.
fn ln_factorial_below(k: usize) -> f64 {
    (2..k).map(|i| libm::log(i as f64)).sum()
}

/// Errors of acquisition ([`crate::tracking::acquisition`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AcquisitionError {
    /// A configuration value, a predicted Doppler, a candidate, a known signal or a margin
    /// was NaN or infinite.
    #[error("non-finite acquisition configuration")]
    NonFinite,
    /// The configuration is out of range (sample rate outside 1.023–64 MHz, IF beyond the
    /// sample rate, Doppler step below 10 Hz, more Doppler bins than the engine holds, zero or
    /// too many milliseconds, a false-alarm probability outside (0, 0.5), a predicted
    /// Doppler beyond [`MAX_DOPPLER_CENTRE_HZ`]), or the engine's
    /// FFT size is not a power of two in 1024–8192.
    #[error("acquisition configuration out of range")]
    InvalidConfig,
    /// Fewer samples than the configured number of milliseconds needs.
    #[error("fewer samples than the search needs")]
    NotEnoughSamples,
    /// The quadrature samples are fewer than the in-phase samples.
    #[error("quadrature samples shorter than in-phase samples")]
    LengthMismatch,
    /// The engine was made with [`Acquisition::blank`] and not built
    /// ([`Acquisition::build`]).
    #[error("acquisition engine not built")]
    NotBuilt,
}

impl Error for AcquisitionError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            _ => ErrorKind::InvalidInput,
        }
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
    use crate::signal::ca_code::CA_CODE_LENGTH;
    use heapless::Vec;

    /// Room for the samples a search of [`config`] reads (8 ms at 2.046 Msps, plus one).
    const SAMPLES: usize = 16_384;
    /// A recording of samples.
    type Samples = Vec<i8, SAMPLES>;

    /// `n` samples of the constant `v`.
    fn constant(v: i8, n: usize) -> Samples {
        core::iter::repeat_n(v, n.min(SAMPLES)).collect()
    }

    const FS: f64 = 2.046e6;

    fn config() -> AcquisitionConfig {
        AcquisitionConfig {
            sample_rate_hz: FS,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 1000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 4,
            false_alarm_probability: 1e-3,
        }
    }

    fn prn(n: u8) -> Prn {
        Prn::new(n).unwrap()
    }

    /// A satellite: PRN, amplitude (LSB per component), Doppler (Hz), code phase (chips).
    type Sat = (u8, f64, f64, f64);

    /// Complex samples: the satellites (no data bits) plus noise of `sigma` LSB, rounded.
    fn samples(sats: &[Sat], sigma: f32, dc: (f64, f64), seed: u64) -> (Samples, Samples) {
        let n = config().samples_needed();
        let mut rng = SplitMix64::new(seed);
        let mut normal = StandardNormal::new();
        let (mut i, mut q) = (Samples::new(), Samples::new());
        for k in 0..n {
            let t = k as f64 / FS;
            let (mut x, mut y) = (dc.0, dc.1);
            for &(p, a, f, tau) in sats {
                let chip = (tau + t * CA_CHIP_RATE_HZ * (1.0 + f / 1575.42e6)) % 1023.0;
                let c = f64::from(prn(p).chip(chip as usize % CA_CODE_LENGTH));
                let ph = core::f64::consts::TAU * f * t;
                x += a * c * libm::cos(ph);
                y += a * c * libm::sin(ph);
            }
            x += f64::from(sigma * normal.sample(&mut rng));
            y += f64::from(sigma * normal.sample(&mut rng));
            i.push(libm::round(x).clamp(-128.0, 127.0) as i8)
                .expect("room for a search");
            q.push(libm::round(y).clamp(-128.0, 127.0) as i8)
                .expect("room for a search");
        }
        (i, q)
    }

    /// The previous evaluation of `ln Q(k, x)` (log-sum-exp over the terms), f64.
    fn ln_gamma_survival_reference(k: usize, x: f64) -> f64 {
        let mut terms = [0.0f64; MAX_NONCOHERENT_MS as usize];
        let (mut max_term, mut ln_term) = (f64::NEG_INFINITY, 0.0f64);
        for (i, t) in terms.iter_mut().enumerate().take(k) {
            if i > 0 {
                ln_term += libm::log(x) - libm::log(i as f64);
            }
            *t = ln_term;
            max_term = max_term.max(ln_term);
        }
        let sum: f64 = terms.iter().take(k).map(|t| libm::exp(t - max_term)).sum();
        -x + max_term + libm::log(sum)
    }

    /// The backward-summed survival function equals the log-sum-exp one to 1e-12 relative
    /// over the thresholds' range (`k` 1–200, `x` from `k` to `200 k`), so the thresholds
    /// (and the false-alarm rate) are the ones they were.
    #[test]
    fn the_fast_survival_function_equals_the_reference() {
        for k in [1usize, 2, 3, 4, 8, 10, 20, 57, 200] {
            let lg = ln_factorial_below(k);
            for t in [1.0f64, 1.3, 2.0, 3.97, 7.5, 30.0, 199.0] {
                let x = k as f64 * t;
                let (a, b) = (
                    ln_gamma_survival(k, x, lg),
                    ln_gamma_survival_reference(k, x),
                );
                assert!(
                    (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                    "k {k} x {x}: {a} {b}"
                );
            }
        }
    }

    fn engine() -> Acquisition<1024> {
        Acquisition::new().unwrap()
    }

    /// A 1- or 2-bit front end's samples searched as bit planes give the very report the
    /// search gives on the same samples decoded to `i8` (complex and real), and the
    /// satellite is detected on both resolutions' planes.
    #[test]
    fn a_search_on_bit_planes_equals_the_search_on_the_decoded_samples() {
        use crate::signal::bitwise::planes::{PlaneBuffer, PlaneFormat, Resolution};
        let (i, q) = samples(&[(7, 3.0, 420.0, 300.2)], 8.0, (0.0, 0.0), 1);
        for resolution in [Resolution::OneBit, Resolution::TwoBit] {
            // the quantizer: sign, and magnitude 3 at or above 8 LSB (about 1 σ)
            let level = |x: &i8| {
                let m = if resolution == Resolution::TwoBit && x.unsigned_abs() >= 8 {
                    3
                } else {
                    1
                };
                if *x < 0 {
                    -m
                } else {
                    m
                }
            };
            let (di, dq): (Samples, Samples) =
                (i.iter().map(level).collect(), q.iter().map(level).collect());
            for complex in [true, false] {
                let mut planes = PlaneBuffer::<512>::new(PlaneFormat {
                    resolution,
                    complex,
                });
                planes.pack_i8(&di, &dq, 2).unwrap();
                let decoded = SearchSamples::decoded(&di, complex.then_some(&dq[..])).unwrap();
                let packed = SearchSamples::Planes(planes.planes());
                let on_planes = engine()
                    .search_report(prn(7), packed, 0, &config())
                    .unwrap();
                let on_decoded = engine()
                    .search_report(prn(7), decoded, 0, &config())
                    .unwrap();
                assert_eq!(on_planes, on_decoded, "{resolution:?}, complex {complex}");
                if complex {
                    assert!(on_planes.result.detected, "{resolution:?}: {on_planes:?}");
                }
            }
        }
    }

    /// A satellite in thermal noise is a candidate, passes the dwell, and comes out at its
    /// Doppler and code phase; the background behaves as the `K` independent milliseconds it
    /// is, so the threshold is the classic one.
    #[test]
    fn a_satellite_in_noise_is_detected_verified_and_located() {
        let (i, q) = samples(&[(7, 3.0, 420.0, 300.2)], 8.0, (0.0, 0.0), 1);
        let r = engine()
            .search_report(prn(7), cx(&i, &q), 0, &config())
            .unwrap();
        assert!(r.candidate && r.result.detected, "{r:?}");
        assert_eq!(r.verification, Verification::Passed);
        assert_eq!(r.effective_ms, 4, "{r:?}");
        let classic = detection_threshold(4, 5120.0, 1e-3);
        assert_eq!(r.result.threshold, classic);
        assert!((r.result.doppler_hz - 420.0).abs() < 150.0, "{r:?}");
        assert!((r.result.code_phase_chips - 300.2).abs() < 0.5, "{r:?}");
    }

    /// A warm start: a satellite at +3.32 kHz lies outside the search's ±1 kHz about zero
    /// (not detected) and inside it about the predicted +3.0 kHz (detected at its Doppler and
    /// code phase, against the same threshold: the same number of cells). A prediction that
    /// is not finite, or beyond any LEO Doppler, is refused.
    #[test]
    fn a_warm_search_about_the_predicted_doppler_finds_what_the_cold_span_misses() {
        let (i, q) = samples(&[(7, 3.0, 3320.0, 300.2)], 8.0, (0.0, 0.0), 1);
        let about_zero = engine()
            .search_report(prn(7), cx(&i, &q), 0, &config())
            .unwrap();
        assert!(!about_zero.result.detected, "{about_zero:?}");
        let near = engine()
            .search_report_near(prn(7), cx(&i, &q), 0, &config(), 3000.0)
            .unwrap();
        assert!(near.result.detected, "{near:?}");
        assert_eq!(near.result.threshold, about_zero.result.threshold);
        assert!((near.result.doppler_hz - 3320.0).abs() < 150.0, "{near:?}");
        assert!(
            (near.result.code_phase_chips - 300.2).abs() < 0.5,
            "{near:?}"
        );
        for (centre, refused) in [
            (f32::NAN, AcquisitionError::NonFinite),
            (f32::INFINITY, AcquisitionError::NonFinite),
            (1.0e5, AcquisitionError::InvalidConfig),
        ] {
            let r = engine().search_report_near(prn(7), cx(&i, &q), 0, &config(), centre);
            assert_eq!(r, Err(refused), "centre {centre}");
        }
    }

    /// A blank engine refuses to search until it is built; built in place, it searches as
    /// one made by `new` (the same report, bit for bit).
    #[test]
    fn a_blank_engine_searches_only_once_built_and_then_as_new() {
        let (i, q) = samples(&[(7, 3.0, 420.0, 300.2)], 8.0, (0.0, 0.0), 1);
        let mut blank = Acquisition::<1024>::blank();
        assert_eq!(
            blank.search(prn(7), &i, Some(&q), 0, &config()),
            Err(AcquisitionError::NotBuilt)
        );
        let candidate = engine().search(prn(7), &i, Some(&q), 0, &config()).unwrap();
        assert_eq!(
            blank
                .cross_check(&candidate, &[], cx(&i, &q), &config(), 1.0)
                .err(),
            Some(AcquisitionError::NotBuilt)
        );
        blank.build().unwrap();
        let built = blank.search_report(prn(7), cx(&i, &q), 0, &config());
        assert_eq!(
            built,
            engine().search_report(prn(7), cx(&i, &q), 0, &config())
        );
        assert!(built.unwrap().result.detected);
        assert_eq!(
            Acquisition::<1000>::blank().build(),
            Err(AcquisitionError::InvalidConfig)
        );
    }

    /// With only the search's samples a candidate is reported but not detected (no dwell).
    #[test]
    fn without_the_dwell_samples_nothing_is_detected() {
        let (i, q) = samples(&[(7, 3.0, 420.0, 300.2)], 8.0, (0.0, 0.0), 2);
        let n = config().search_samples();
        let r = engine()
            .search_report(prn(7), cx(&i[..n], &q[..n]), 0, &config())
            .unwrap();
        assert!(r.candidate && !r.result.detected);
        assert_eq!(r.verification, Verification::NoSamples);
        assert_eq!(
            engine().search(prn(7), &i[..n - 1], Some(&q[..n - 1]), 0, &config()),
            Err(AcquisitionError::NotEnoughSamples)
        );
    }

    /// Issue 15: `doppler_max_hz: 1e30` made `doppler_bins()` overflow (`2 · usize::MAX`);
    /// the count now saturates and the search refuses the configuration.
    #[test]
    fn a_huge_doppler_span_does_not_overflow_doppler_bins() {
        let huge = AcquisitionConfig {
            doppler_max_hz: 1e30,
            ..config()
        };
        assert_eq!(huge.doppler_bins(), usize::MAX);
        let n = config().samples_needed();
        let (i, q) = (constant(1, n), constant(-1, n));
        assert_eq!(
            engine().search(prn(3), &i, Some(&q), 0, &huge),
            Err(AcquisitionError::InvalidConfig)
        );
        assert_eq!(config().doppler_bins(), 5);
    }

    /// Issue 15: `samples_needed()` overflowed for a sample rate of +∞ (`usize::MAX + 1`); it
    /// now saturates (NaN gives 1) and the search refuses the configuration.
    #[test]
    fn an_infinite_sample_rate_does_not_overflow_samples_needed() {
        let inf = AcquisitionConfig {
            sample_rate_hz: f64::INFINITY,
            ..config()
        };
        assert_eq!(inf.samples_needed(), usize::MAX);
        assert_eq!(inf.search_samples(), usize::MAX);
        let nan = AcquisitionConfig {
            sample_rate_hz: f64::NAN,
            ..config()
        };
        assert_eq!(nan.samples_needed(), 1);
        let n = config().samples_needed();
        let (i, q) = (constant(1, n), constant(-1, n));
        for bad in [inf, nan] {
            assert_eq!(
                engine().search(prn(3), &i, Some(&q), 0, &bad),
                Err(AcquisitionError::NonFinite)
            );
        }
    }

    /// Constant, saturated and silent inputs detect nothing for any PRN; a DC offset on a
    /// noisy satellite does not hide it.
    #[test]
    fn degenerate_inputs_detect_nothing() {
        let n = config().samples_needed();
        let mut e = engine();
        for value in [0i8, 127, -128, 20] {
            let (i, q) = (constant(value, n), constant(value / 2, n));
            for p in 1..=32 {
                let r = e.search(prn(p), &i, Some(&q), 0, &config()).unwrap();
                assert!(!r.detected, "constant {value}: PRN {p} {r:?}");
            }
        }
        let (i, q) = samples(&[(7, 3.0, 420.0, 300.2)], 8.0, (20.0, -13.0), 3);
        let r = e.search(prn(7), &i, Some(&q), 0, &config()).unwrap();
        assert!(r.detected && (r.doppler_hz - 420.0).abs() < 150.0, "{r:?}");
    }

    /// A noise-free strong satellite: another PRN's search sees its cross-correlation, which
    /// repeats every millisecond; the background's effective milliseconds drop and no absent
    /// PRN is detected. Handed the absent PRN's strongest peak, the cross-correlation test
    /// names the strong satellite; a real weaker satellite is not explained.
    #[test]
    fn cross_correlation_is_neither_detected_nor_accepted() {
        let strong: Sat = (5, 40.0, 1000.0, 100.0);
        let (i, q) = samples(&[strong], 0.0, (0.0, 0.0), 4);
        let mut e = engine();
        let known = [KnownSignal {
            prn: prn(5),
            doppler_hz: 1000.0,
            code_phase_chips: 100.0,
        }];
        let mut explained = 0;
        for p in (1..=32).filter(|&p| p != 5) {
            let r = e.search_report(prn(p), cx(&i, &q), 0, &config()).unwrap();
            assert!(!r.result.detected, "PRN {p}: {r:?}");
            assert!(r.effective_ms < 4, "PRN {p}: {r:?}");
            let check = e
                .cross_check(
                    &r.result,
                    &known,
                    cx(&i, &q),
                    &config(),
                    CROSS_CORRELATION_MARGIN,
                )
                .unwrap();
            // The prediction holds every peak to within 4 dB (the margin is 3 dB).
            assert!(
                check.power <= 2.5 * check.predicted_power,
                "PRN {p}: {check:?}"
            );
            if check.explained {
                assert_eq!(check.source, Some(prn(5)));
                explained += 1;
            }
        }
        // Nearly every absent PRN's strongest peak is explained as the strong satellite's
        // cross-correlation (none is detected in the first place). (The prediction counts
        // only the excess over the mean cross-correlation, which the background holds: one
        // peak, PRN 23's, stands 3.4 dB over it.)
        assert!(explained >= 30, "{explained} of 31");
        let weak: Sat = (9, 6.0, -500.0, 700.4);
        let (i, q) = samples(&[strong, weak], 0.0, (0.0, 0.0), 5);
        let r = e.search(prn(9), &i, Some(&q), 0, &config()).unwrap();
        assert!(r.detected, "{r:?}");
        let check = e
            .cross_check(&r, &known, cx(&i, &q), &config(), CROSS_CORRELATION_MARGIN)
            .unwrap();
        assert!(!check.explained, "{check:?}");
    }

    /// Cancelling a noise-free strong satellite (its search's Doppler and code phase, off by
    /// a fraction of a bin: the cancellation refines them) removes its cross-correlation:
    /// every absent PRN's strongest peak loses most of its power (it was the strong
    /// satellite's) and the background returns to thermal; a real weak satellite keeps its
    /// power and is detected in the search with the strong one cancelled.
    #[test]
    fn cancelling_a_strong_satellite_removes_its_cross_correlation() {
        let strong: Sat = (5, 40.0, 1000.0, 100.0);
        let weak: Sat = (9, 3.0, -500.0, 700.4);
        let (i, q) = samples(&[strong, weak], 8.0, (0.0, 0.0), 6);
        let mut e = engine();
        let found = e.search(prn(5), &i, Some(&q), 0, &config()).unwrap();
        assert!(found.detected, "{found:?}");
        let known = [KnownSignal::from(&found)];
        let mut worst = 0.0f32;
        for p in (1..=32).filter(|&p| p != 5 && p != 9) {
            let r = e.search_report(prn(p), cx(&i, &q), 0, &config()).unwrap();
            let check = e
                .cancellation_check(
                    &r.result,
                    &known,
                    cx(&i, &q),
                    &config(),
                    CANCELLATION_KEEP_FRACTION,
                )
                .unwrap();
            assert_eq!(check.cancelled, 1);
            worst = worst.max(check.cancelled_power / check.power);
            let c = e
                .search_report_cancelling(prn(p), cx(&i, &q), 0, &config(), &known)
                .unwrap();
            assert!(!c.result.detected, "PRN {p}: {c:?}");
        }
        assert!(worst < CANCELLATION_KEEP_FRACTION, "{worst}");
        // The strong satellite's cross-correlation dominates the noise: without the
        // cancellation the background repeats every millisecond, with it it is thermal.
        let plain = e.search_report(prn(9), cx(&i, &q), 0, &config()).unwrap();
        let r = e
            .search_report_cancelling(prn(9), cx(&i, &q), 0, &config(), &known)
            .unwrap();
        assert!(plain.effective_ms < 4, "{plain:?}");
        assert!(r.result.detected, "{r:?}");
        assert_eq!(r.effective_ms, 4, "{r:?}");
        assert!(r.noise_floor < 0.5 * plain.noise_floor, "{r:?} {plain:?}");
        assert!((r.result.doppler_hz + 500.0).abs() < 150.0, "{r:?}");
        let check = e
            .cancellation_check(
                &r.result,
                &known,
                cx(&i, &q),
                &config(),
                CANCELLATION_KEEP_FRACTION,
            )
            .unwrap();
        assert!(check.kept, "{check:?}");
    }
}
