//! C/N0 and phase-lock statistics from the prompt and noise taps.
//!
//! The noise tap correlates the same samples with the code at a quiet offset, so its power is
//! the noise power of the prompt tap, `E|N|² = 2σ²`, while `E|P|² = A² + 2σ²`. Over a window
//! of `W` epochs of `T` seconds:
//!
//! ```text
//! C/N0 = (mean|P|² − mean|N|²) / (mean|N|² · T)                       (ratio to dB-Hz)
//! PLD  = (mean I_P² − mean Q_P²) / (mean|P|² − mean|N|²)  ≈ cos 2Δφ     (phase lock)
//! ```
//! Both are insensitive to data bits and need no bit synchronization; the noise subtraction
//! keeps the phase-lock indicator near 1 in lock even at 35 dB-Hz, where the uncorrected
//! `(I² − Q²)/(I² + Q²)` of 1 ms sums would sit at 0.76.

use crate::signal::correlator::Iq;

/// Window statistics of the prompt and noise taps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PowerWindow {
    sum_i2: f32,
    sum_q2: f32,
    sum_n2: f32,
    count: u32,
}

/// The result of a completed window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WindowEstimate {
    /// C/N0, dB-Hz (clamped to 0–99).
    pub cn0_dbhz: f32,
    /// Phase-lock indicator, ≈ cos 2Δφ (clamped to −1…1).
    pub phase_lock_indicator: f32,
}

impl PowerWindow {
    /// Adds one epoch. Powers are scaled by 2⁻²⁰ to stay well inside f32 over long windows.
    pub fn add(&mut self, prompt: &Iq, noise: &Iq) {
        const S: f32 = 1.0 / 1_048_576.0;
        let (i, q) = (prompt.i as f32, prompt.q as f32);
        self.sum_i2 += i * i * S;
        self.sum_q2 += q * q * S;
        self.sum_n2 += noise.power() * S;
        self.count += 1;
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
        let (pi, pq, pn) = (self.sum_i2 / n, self.sum_q2 / n, self.sum_n2 / n);
        *self = Self::default();
        let signal = pi + pq - pn;
        let ratio = if pn > 0.0 { signal / (pn * t) } else { 0.0 };
        let cn0 = if ratio > 1.0 {
            10.0 * libm::log10f(ratio)
        } else {
            0.0
        };
        let pld = if signal > 0.0 {
            (pi - pq) / signal
        } else {
            0.0
        };
        Some(WindowEstimate {
            cn0_dbhz: cn0.clamp(0.0, 99.0),
            phase_lock_indicator: if pld.is_finite() {
                pld.clamp(-1.0, 1.0)
            } else {
                0.0
            },
        })
    }
}
