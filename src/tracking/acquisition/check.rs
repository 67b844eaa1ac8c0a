//! The cross-correlation test of a detection against the stronger satellites already
//! detected or tracked, with every signal's power measured on the searched samples by a
//! direct correlation.

#[cfg(doc)]
use super::CROSS_CORRELATION_MARGIN;
use super::{
    check_inputs, check_known, Acquisition, AcquisitionConfig, AcquisitionError, SearchResult,
    SearchSamples,
};
use crate::signal::ca_code::{Prn, CA_CODE_LENGTH};
use crate::tracking::xcorr::{
    cross_correlation_source, CrossCorrelationTest, SignalProbe, MAX_OTHERS,
};

/// A satellite already known on the samples a candidate was found in: detected in the same
/// search round, or tracked by a channel.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KnownSignal {
    /// The satellite.
    pub prn: Prn,
    /// Its Doppler, Hz.
    pub doppler_hz: f32,
    /// Its code phase at the first sample searched, chips in `[0, 1023)`.
    pub code_phase_chips: f64,
}

impl From<&SearchResult> for KnownSignal {
    fn from(r: &SearchResult) -> Self {
        Self {
            prn: r.prn,
            doppler_hz: r.doppler_hz,
            code_phase_chips: f64::from(r.code_phase_chips),
        }
    }
}

/// The outcome of [`Acquisition::cross_check`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CrossCheck {
    /// The candidate is the cross-correlation of stronger signals: not a satellite.
    pub explained: bool,
    /// The stronger signal that contributes most (`None`: none stronger).
    pub source: Option<Prn>,
    /// The candidate's power over the background, engine units.
    pub power: f32,
    /// The cross-correlation power predicted at the candidate, same units.
    pub predicted_power: f32,
}

/// The outcome of [`Acquisition::cancellation_check`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CancellationCheck {
    /// The candidate keeps at least the configured fraction of its power with the known
    /// signals cancelled: a satellite of its own.
    pub kept: bool,
    /// Known signals cancelled.
    pub cancelled: usize,
    /// The candidate's power over the background, engine units.
    pub power: f32,
    /// The same with the known signals cancelled.
    pub cancelled_power: f32,
}

/// A candidate is a satellite of its own when it keeps at least this fraction of its power
/// (background removed) with the known signals cancelled from the samples (−3 dB; another
/// satellite's cross-correlation keeps what the cancellation leaves of that satellite).
pub const CANCELLATION_KEEP_FRACTION: f32 = 0.5;

impl<const N: usize, const L: usize> Acquisition<N, L> {
    /// Tests `candidate` (a result of a search on `i`, `q`) by cancelling the `known`
    /// signals from the samples ([`Acquisition::search_report_cancelling`]'s cancellation):
    /// its power at its Doppler and code phase over the search's `K` ms, background removed,
    /// without and with the cancellation; it is `kept` when the second is at least
    /// `keep_fraction` times the first ([`CANCELLATION_KEEP_FRACTION`] is the receiver's
    /// choice). A peak that is the cross-correlation of known signals loses what the
    /// cancellation removes of them; a satellite keeps its own power.
    ///
    /// Bounded: `2 · K` iterations of one millisecond of samples (the second with one pass
    /// per known signal) and two `N`-point FFTs, and the known signals' refinement.
    ///
    /// # Errors
    /// As [`Acquisition::search`], and [`AcquisitionError::NonFinite`] for a non-finite
    /// candidate, known signal or fraction.
    pub fn cancellation_check(
        &mut self,
        candidate: &SearchResult,
        known: &[KnownSignal],
        samples: SearchSamples<'_>,
        config: &AcquisitionConfig,
        keep_fraction: f32,
    ) -> Result<CancellationCheck, AcquisitionError> {
        self.check_built()?;
        check_inputs(samples, config)?;
        let victim = KnownSignal::from(candidate);
        check_known(known)?;
        check_known(core::slice::from_ref(&victim))?;
        if !keep_fraction.is_finite() {
            return Err(AcquisitionError::NonFinite);
        }
        let dc = samples.mean(config.samples_needed());
        self.prepare_interference(samples, config, dc);
        let power = self.signal_power(&victim, false, samples, config, dc);
        let cancelled = self.set_cancellation(candidate.prn, known, samples, config, dc);
        let cancelled_power = self.signal_power(&victim, false, samples, config, dc);
        Ok(CancellationCheck {
            kept: cancelled_power >= keep_fraction * power,
            cancelled,
            power,
            cancelled_power,
        })
    }

    /// Tests `candidate` (a result of a search on `i`, `q`) against the cross-correlation of
    /// the `known` signals that are stronger on these samples: each signal's power is
    /// measured on the search's `K` ms by the engine's own correlation at its Doppler (the
    /// peak near its code phase, interpolated, over the mean of that Doppler bin's
    /// background); the candidate is explained when its power is at most `margin` times the
    /// stronger ones' predicted cross-correlation ([`crate::tracking::xcorr`];
    /// [`CROSS_CORRELATION_MARGIN`] is the receiver's choice). Entries of the candidate's PRN
    /// are skipped; at most [`MAX_OTHERS`] are used.
    ///
    /// Bounded: `(1 + known) · K` iterations of one millisecond of samples and two `N`-point
    /// FFTs, and [`crate::tracking::xcorr::GRID_POINTS`] `· known` code cross-correlations.
    ///
    /// # Errors
    /// As [`Acquisition::search`], and [`AcquisitionError::NonFinite`] for a non-finite
    /// candidate, known signal or margin.
    pub fn cross_check(
        &mut self,
        candidate: &SearchResult,
        known: &[KnownSignal],
        samples: SearchSamples<'_>,
        config: &AcquisitionConfig,
        margin: f32,
    ) -> Result<CrossCheck, AcquisitionError> {
        self.check_built()?;
        check_inputs(samples, config)?;
        let finite = |d: f32, c: f64| d.is_finite() && c.is_finite();
        if !margin.is_finite()
            || !finite(candidate.doppler_hz, f64::from(candidate.code_phase_chips))
            || known
                .iter()
                .any(|k| !finite(k.doppler_hz, k.code_phase_chips))
        {
            return Err(AcquisitionError::NonFinite);
        }
        let dc = samples.mean(config.samples_needed());
        self.prepare_interference(samples, config, dc);
        let mut probe = |s: &KnownSignal, interpolate: bool| SignalProbe {
            prn: s.prn,
            sample: 0,
            code_phase_chips: s.code_phase_chips,
            code_chips_per_sample: 0.0,
            doppler_hz: s.doppler_hz,
            power: self.signal_power(s, interpolate, samples, config, dc),
        };
        // The candidate's strongest cell as it is (a cross-correlation peak is no triangle:
        // interpolating it as one would inflate it); the known signals' triangles
        // interpolated (their full power makes the cross-correlation they put there).
        let victim = probe(&KnownSignal::from(candidate), false);
        let mut others = [victim; MAX_OTHERS];
        let mut count = 0usize;
        let distinct = known.iter().filter(|k| k.prn != candidate.prn);
        for (slot, k) in others.iter_mut().zip(distinct) {
            *slot = probe(k, true);
            count = count.saturating_add(1);
        }
        let test = CrossCorrelationTest {
            epoch_aligned: false,
            doppler_tolerance_hz: 0.25 * config.doppler_step_hz,
            // One code bin: the candidate's peak is located to within it.
            lag_tolerance_chips: CA_CODE_LENGTH as f64 / N as f64,
            coherence_hz: 1000.0 / f32::from(config.noncoherent_ms),
            margin,
        };
        let verdict = cross_correlation_source(&victim, others.get(..count).unwrap_or(&[]), &test);
        Ok(CrossCheck {
            explained: verdict.explained,
            source: verdict.strongest_source,
            power: victim.power,
            predicted_power: verdict.predicted_power,
        })
    }

    /// A signal's power on the first `K` ms: the engine's correlation at its Doppler, the
    /// strongest cell within one code bin of its code phase (`interpolate`: with the
    /// correlation triangle's peak interpolated), less the mean background cell of that
    /// Doppler bin. Engine units.
    fn signal_power(
        &mut self,
        s: &KnownSignal,
        interpolate: bool,
        samples: SearchSamples<'_>,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> f32 {
        self.prepare_code(s.prn);
        let len = CA_CODE_LENGTH as f64;
        let phase = s.code_phase_chips - libm::floor(s.code_phase_chips / len) * len;
        let centre = libm::round(N as f64 * (1.0 - phase / len)) as usize & (N - 1);
        let (peak, floor) = self.measure_at(samples, s.doppler_hz, centre, interpolate, config, dc);
        (peak - floor).max(0.0)
    }
}
