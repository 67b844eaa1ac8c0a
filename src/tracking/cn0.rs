//! C/N0, phase-lock and correlation-shape statistics from the early, prompt, late and noise
//! taps.
//!
//! The noise tap correlates the same samples with the code at a quiet offset, so its power is
//! the noise power of the prompt tap, `E|N|² = 2σ²`, while `E|P|² = A² + 2σ²`. Over a window
//! of `W` epochs of `T` seconds:
//!
//! ```text
//! C/N0  = (mean|P|² − mean|N|²) / (mean|N|² · T)                      (ratio to dB-Hz)
//! PLD   = (mean I_P² − mean Q_P²) / (mean|P|² − mean|N|²)  ≈ cos 2Δφ    (phase lock)
//! shape = (½(mean|E|² + mean|L|²) − mean|N|²) / (mean|P|² − mean|N|²)    (≈ (1 − d)² on a
//!                                                                       correlation peak)
//! ```
//! All are insensitive to data bits and need no bit synchronization; the noise subtraction
//! keeps the phase-lock indicator near 1 in lock even at 35 dB-Hz, where the uncorrected
//! `(I² − Q²)/(I² + Q²)` of 1 ms sums would sit at 0.76. The shape is `(1 − d)²` (0.25 for
//! `d` = 0.5 chip) on a satellite's correlation triangle and near 1 where the correlation does
//! not depend on the code phase (a tone, a DC offset) or on a cross-correlation plateau.
//!
//! # Noise below the quantization floor
//! The samples are integers: even without thermal noise their rounding leaves at least
//! `1/12` LSB² per component and sample, so the noise tap cannot honestly read less than
//! `127² · n · c / 12` per epoch of `n` samples (`c` = 2 components for complex samples, 1 for
//! real; 127 the carrier table's amplitude). A noise-free recording (signal simulators add no
//! noise) reads about that, or less: below the floor the noise is taken at the floor, which
//! keeps C/N0 finite, and an estimate whose noise is within [`QUANTIZATION_MARGIN`] of the
//! floor is flagged ([`WindowEstimate::quantization_limited`]): its C/N0 is the signal over the
//! samples' rounding, not over thermal noise.

use crate::signal::correlator::{Iq, Taps};
use crate::signal::nco::CARRIER_AMPLITUDE;

/// Power scale of the window sums (keeps them well inside f32 over long windows).
const POWER_SCALE: f32 = 1.0 / 1_048_576.0;

/// Largest C/N0 reported, dB-Hz.
pub const MAX_CN0_DBHZ: f32 = 99.0;

/// Uniform rounding noise per component and sample, LSB².
const ROUNDING_NOISE_LSB2: f32 = 1.0 / 12.0;

/// A noise estimate below this many times the quantization floor is the rounding's, not
/// thermal noise (3 dB).
pub const QUANTIZATION_MARGIN: f32 = 2.0;

/// Window statistics of the reference antenna's taps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PowerWindow {
    sum_i2: f32,
    sum_q2: f32,
    sum_n2: f32,
    sum_el2: f32,
    sum_floor: f32,
    count: u32,
}

/// The result of a completed window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WindowEstimate {
    /// C/N0, dB-Hz (clamped to 0–[`MAX_CN0_DBHZ`]).
    pub cn0_dbhz: f32,
    /// Phase-lock indicator, ≈ cos 2Δφ (clamped to −1…1).
    pub phase_lock_indicator: f32,
    /// Early/late over prompt signal power (the correlation shape; ≈ `(1 − d)²` in lock, 1
    /// when no signal power).
    pub shape: f32,
    /// Prompt signal power `mean|P|² − mean|N|²` per epoch, 2⁻²⁰ units (0 at most).
    pub signal_power: f32,
    /// The noise tap read less than [`QUANTIZATION_MARGIN`] times the quantization floor
    /// (the floor was used when below it): the C/N0 is the signal over the samples'
    /// rounding.
    pub quantization_limited: bool,
    /// Epochs in the window.
    pub epochs: u32,
}

impl PowerWindow {
    /// Adds one epoch of the prompt and noise taps alone (values that are no sums of integer
    /// samples: no quantization floor). Without early and late taps the shape is not
    /// measured: it reads 1 (no correlation peak), never a triangle.
    pub fn add(&mut self, prompt: &Iq, noise: &Iq) {
        let (i, q) = (prompt.i as f32, prompt.q as f32);
        self.sum_i2 += i * i * POWER_SCALE;
        self.sum_q2 += q * q * POWER_SCALE;
        self.sum_n2 += noise.power() * POWER_SCALE;
        self.sum_el2 += prompt.power() * POWER_SCALE;
        // (epochs in the window: saturates rather than wraps)
        self.count = self.count.saturating_add(1);
    }

    /// Adds one epoch of the reference antenna's taps over `samples` samples (`complex`:
    /// I/Q samples), with the samples' quantization floor and the correlation shape.
    pub fn add_taps(&mut self, taps: &Taps, samples: u32, complex: bool) {
        let components = if complex { 2.0 } else { 1.0 };
        let amplitude = f32::from(CARRIER_AMPLITUDE);
        let floor = amplitude * amplitude * components * ROUNDING_NOISE_LSB2;
        self.add_taps_with_floor(taps, samples, floor);
    }

    /// Adds one epoch of taps as [`add_taps`](Self::add_taps), with the rounding floor of the
    /// correlator that made them: `floor_per_sample` is the noise tap's power per sample that
    /// the samples' rounding alone leaves
    /// ([`Correlate::rounding_noise_per_sample`](crate::signal::Correlate::rounding_noise_per_sample)).
    #[inline]
    pub fn add_taps_with_floor(&mut self, taps: &Taps, samples: u32, floor_per_sample: f32) {
        let (i, q) = (taps.prompt.i as f32, taps.prompt.q as f32);
        self.sum_i2 += i * i * POWER_SCALE;
        self.sum_q2 += q * q * POWER_SCALE;
        self.sum_n2 += taps.noise.power() * POWER_SCALE;
        self.sum_el2 += 0.5 * (taps.early.power() + taps.late.power()) * POWER_SCALE;
        self.sum_floor += floor_per_sample * samples as f32 * POWER_SCALE;
        // (epochs in the window: saturates rather than wraps)
        self.count = self.count.saturating_add(1);
    }

    /// Epochs in the window.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The estimate for epochs of `t` seconds, and a reset window. `None` for an empty window.
    pub fn finish(&mut self, t: f32) -> Option<WindowEstimate> {
        if self.count == 0 || !(t > 0.0) {
            return None;
        }
        let n = self.count as f32;
        let (pi, pq, pel) = (self.sum_i2 / n, self.sum_q2 / n, self.sum_el2 / n);
        let (measured_noise, floor) = (self.sum_n2 / n, self.sum_floor / n);
        let epochs = self.count;
        *self = Self::default();
        let quantization_limited = measured_noise < QUANTIZATION_MARGIN * floor;
        let pn = measured_noise.max(floor);
        let signal = pi + pq - pn;
        let ratio = if pn > 0.0 { signal / (pn * t) } else { 0.0 };
        let cn0 = if ratio > 1.0 {
            10.0 * libm::log10f(ratio)
        } else {
            0.0
        };
        let bounded = |x: f32, lo: f32, hi: f32, otherwise: f32| {
            if x.is_finite() {
                x.clamp(lo, hi)
            } else {
                otherwise
            }
        };
        let (pld, shape) = if signal > 0.0 {
            ((pi - pq) / signal, (pel - pn) / signal)
        } else {
            (0.0, 1.0)
        };
        Some(WindowEstimate {
            cn0_dbhz: bounded(cn0, 0.0, MAX_CN0_DBHZ, 0.0),
            phase_lock_indicator: bounded(pld, -1.0, 1.0, 0.0),
            shape: bounded(shape, 0.0, 1.0, 1.0),
            signal_power: signal.max(0.0),
            quantization_limited,
            epochs,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn taps(p: (i32, i32), el: i32, n: (i32, i32)) -> Taps {
        Taps {
            early: Iq { i: el, q: 0 },
            prompt: Iq { i: p.0, q: p.1 },
            late: Iq { i: el, q: 0 },
            noise: Iq { i: n.0, q: n.1 },
        }
    }

    /// A noise-free prompt (noise tap 0) gives a finite C/N0 from the quantization floor,
    /// flagged; with noise above the floor the estimate is the plain one, unflagged; the
    /// correlation triangle's shape is (1 − d)², a flat correlation's 1.
    #[test]
    fn the_noise_floor_keeps_cn0_finite_and_says_so() {
        let mut w = PowerWindow::default();
        for _ in 0..100 {
            w.add_taps(&taps((2_000_000, 0), 1_000_000, (0, 0)), 2600, true);
        }
        let e = w.finish(1e-3).unwrap();
        let floor = 127.0f32 * 127.0 * 2600.0 * 2.0 / 12.0;
        let expected = 10.0 * ((2.0e6f32 * 2.0e6 - floor) / (floor * 1e-3)).log10();
        assert!(e.quantization_limited);
        assert!((e.cn0_dbhz - expected).abs() < 0.05, "{e:?} vs {expected}");
        assert!((e.shape - 0.25).abs() < 0.01, "{e:?}");
        let mut w = PowerWindow::default();
        for _ in 0..100 {
            w.add_taps(&taps((200_000, 0), 200_000, (20_000, 0)), 2600, true);
        }
        let e = w.finish(1e-3).unwrap();
        let expected = 10.0 * ((200_000.0f32.powi(2) - 4e8) / (4e8 * 1e-3)).log10();
        assert!(!e.quantization_limited);
        assert!((e.cn0_dbhz - expected).abs() < 0.05, "{e:?} vs {expected}");
        assert!(e.shape > 0.99, "{e:?}");
        assert!(PowerWindow::default().finish(1e-3).is_none());
    }
}
