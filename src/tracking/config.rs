//! Configuration of a tracking channel.

use super::lock::LockThresholds;
use crate::signal::correlator::{CorrelatorConfig, SlaveTaps};
use crate::tracking::TrackingError;

/// Configuration of a channel (front end and loop parameters).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelConfig {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz.
    pub intermediate_frequency_hz: f64,
    /// Early/late offset from prompt, chips.
    pub early_late_offset_chips: f32,
    /// Taps of the slaved antennas (all four by default).
    pub slave_taps: SlaveTaps,
    /// Duration of the pull-in schedule after hand-over, ms.
    pub pull_in_ms: u32,
    /// PLL noise bandwidth, Hz.
    pub pll_bandwidth_hz: f32,
    /// FLL-assist bandwidth during pull-in, Hz.
    pub fll_pull_in_bandwidth_hz: f32,
    /// FLL-assist bandwidth after pull-in, Hz (0: pure PLL).
    pub fll_bandwidth_hz: f32,
    /// DLL bandwidth during pull-in, Hz.
    pub dll_pull_in_bandwidth_hz: f32,
    /// DLL bandwidth after pull-in, Hz.
    pub dll_bandwidth_hz: f32,
    /// Lock-detector window, epochs.
    pub lock_window: u16,
    /// C/N0 reporting window, epochs.
    pub cn0_window: u16,
    /// Code-lock C/N0 threshold, dB-Hz.
    pub cn0_lock_threshold_dbhz: f32,
    /// Phase-lock indicator threshold (≈ cos 2Δφ).
    pub pld_threshold: f32,
    /// Largest correlation shape (early/late over prompt signal power) of a good lock window
    /// (midway between a correlation peak's `(1 − d)²` and a flat correlation's 1).
    pub max_correlation_shape: f32,
    /// Good lock windows in a row that declare the code lock (the phase lock follows at the
    /// first good phase window after it).
    pub lock_windows_to_declare: u8,
    /// Bad lock windows in a row that lose it.
    pub lock_windows_to_lose: u8,
    /// A channel is another satellite's cross-correlation when its prompt power is at most
    /// this times the predicted cross-correlation of the stronger channels
    /// ([`crate::tracking::Channel::check_cross_correlation`]).
    pub cross_correlation_margin: f32,
    /// Lock windows in a row explained as a cross-correlation before the channel releases
    /// itself.
    pub cross_correlation_windows: u8,
    /// Largest Doppler rate the frequency refinement estimates, Hz/s (0: no rate estimate, the
    /// loop starts with rate 0, as suits a ground receiver). Receivers in low Earth orbit see
    /// up to about ±60 Hz/s on GPS L1; see [`ChannelConfig::leo`].
    pub max_doppler_rate_hz_s: f32,
}

impl ChannelConfig {
    /// The defaults for a front end: 0.5 chip offset, 15 Hz PLL, FLL assist 2 Hz for 300 ms
    /// of pull-in then off (pure PLL), DLL 2 Hz then 0.5 Hz, 100 ms lock windows, 1 s C/N0
    /// windows, code lock above 26 dB-Hz with a correlation peak (shape ≤ 0.625), phase lock
    /// above cos 2Δφ = 0.5, code lock declared after 2 good windows (200 ms), both lost after
    /// 3 bad ones;
    /// a channel explained as a cross-correlation (within 3 dB) in 2 windows releases itself.
    pub fn new(sample_rate_hz: f64, intermediate_frequency_hz: f64) -> Self {
        Self {
            sample_rate_hz,
            intermediate_frequency_hz,
            early_late_offset_chips: 0.5,
            slave_taps: SlaveTaps::All,
            pull_in_ms: 300,
            pll_bandwidth_hz: 15.0,
            fll_pull_in_bandwidth_hz: 2.0,
            fll_bandwidth_hz: 0.0,
            dll_pull_in_bandwidth_hz: 2.0,
            dll_bandwidth_hz: 0.5,
            lock_window: 100,
            cn0_window: 1000,
            cn0_lock_threshold_dbhz: 26.0,
            pld_threshold: 0.5,
            max_correlation_shape: 0.625,
            lock_windows_to_declare: 2,
            lock_windows_to_lose: 3,
            cross_correlation_margin: 2.0,
            cross_correlation_windows: 2,
            max_doppler_rate_hz_s: 0.0,
        }
    }

    /// [`ChannelConfig::new`] with the Doppler-rate estimate of the refinement stage enabled up
    /// to ±150 Hz/s (LEO dynamics: the carrier loop starts with the estimated rate and the
    /// Doppler extrapolated to the end of the refinement window).
    pub fn leo(sample_rate_hz: f64, intermediate_frequency_hz: f64) -> Self {
        Self {
            max_doppler_rate_hz_s: 150.0,
            ..Self::new(sample_rate_hz, intermediate_frequency_hz)
        }
    }

    pub(crate) fn lock_thresholds(&self) -> LockThresholds {
        LockThresholds {
            cn0_dbhz: self.cn0_lock_threshold_dbhz,
            pld: self.pld_threshold,
            max_shape: self.max_correlation_shape,
            windows_to_declare: self.lock_windows_to_declare,
            windows_to_lose: self.lock_windows_to_lose,
        }
    }

    pub(crate) fn correlator(&self) -> CorrelatorConfig {
        CorrelatorConfig {
            sample_rate_hz: self.sample_rate_hz,
            intermediate_frequency_hz: self.intermediate_frequency_hz,
            early_late_offset_chips: self.early_late_offset_chips,
            slave_taps: self.slave_taps,
        }
    }

    pub(crate) fn validate(&self) -> Result<(), TrackingError> {
        let v = [
            self.pll_bandwidth_hz,
            self.fll_pull_in_bandwidth_hz,
            self.fll_bandwidth_hz,
            self.dll_pull_in_bandwidth_hz,
            self.dll_bandwidth_hz,
            self.cn0_lock_threshold_dbhz,
            self.pld_threshold,
            self.max_correlation_shape,
            self.cross_correlation_margin,
            self.max_doppler_rate_hz_s,
        ];
        if v.iter().any(|x| !x.is_finite()) {
            return Err(TrackingError::NonFinite);
        }
        let bw_ok = |b: f32| (0.0..=100.0).contains(&b);
        let bandwidths_ok = bw_ok(self.pll_bandwidth_hz)
            && bw_ok(self.fll_pull_in_bandwidth_hz)
            && bw_ok(self.fll_bandwidth_hz)
            && bw_ok(self.dll_pull_in_bandwidth_hz)
            && bw_ok(self.dll_bandwidth_hz);
        let rate_ok = (0.0..=1000.0).contains(&self.max_doppler_rate_hz_s);
        let lock_ok = self.max_correlation_shape > 0.0
            && self.max_correlation_shape <= 1.0
            && self.lock_windows_to_declare > 0
            && self.lock_windows_to_lose > 0
            && self.cross_correlation_margin >= 0.0
            && self.cross_correlation_windows > 0;
        if !bandwidths_ok || !rate_ok || !lock_ok || self.lock_window == 0 || self.cn0_window == 0 {
            return Err(TrackingError::InvalidConfig);
        }
        Ok(())
    }
}
