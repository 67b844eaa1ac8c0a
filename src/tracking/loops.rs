//! Discriminators and loop filters of the tracking loops (1 ms updates on the reference
//! antenna's correlators).
//!
//! * Carrier: an FLL-assisted PLL, Kaplan & Hegarty, *Understanding GPS/GNSS* (3rd ed.),
//!   §8.8 (the 3rd-order PLL with 2nd-order FLL assist), with the Costas discriminator
//!   `atan(Q/I)` (insensitive to data-bit sign flips) and the cross/dot FLL discriminator
//!   `atan(cross/dot)/(2πT)` (also bit-tolerant; range ±1/(4T) = ±250 Hz at 1 ms).
//! * Code: the normalized early-minus-late envelope DLL `(1 − δ)(|E| − |L|)/(|E| + |L|)`
//!   chips (δ = early/late offset), exact for |error| ≤ δ on the ideal triangle, in a
//!   1st-order carrier-aided loop.
//!
//! Phases are in cycles, frequencies in Hz (the loop equations scale by 2π uniformly, so the
//! radian forms of the reference hold unchanged).

use crate::signal::correlator::Iq;

/// Costas discriminator: phase error in cycles, `atan(Q/I)/2π ∈ [−¼, ¼]` (0 when `I = 0`).
pub fn costas_cycles(p: &Iq) -> f32 {
    let (i, q) = (p.i as f32, p.q as f32);
    if i == 0.0 {
        return 0.0;
    }
    libm::atanf(q / i) / core::f32::consts::TAU
}

/// Cross/dot FLL discriminator on two consecutive prompts `T` seconds apart: frequency
/// error in Hz, `atan(cross/dot)/(2πT)` (bit-tolerant, range ±1/(4T)).
pub fn fll_hz(previous: &Iq, current: &Iq, t: f32) -> f32 {
    let (i1, q1, i2, q2) = (
        previous.i as f32,
        previous.q as f32,
        current.i as f32,
        current.q as f32,
    );
    let cross = i1 * q2 - q1 * i2;
    let dot = i1 * i2 + q1 * q2;
    if dot == 0.0 || !(t > 0.0) {
        return 0.0;
    }
    libm::atanf(cross / dot) / (core::f32::consts::TAU * t)
}

/// Normalized early-minus-late envelope discriminator: code error in chips (positive when the
/// signal is ahead of the prompt replica), for early/late offset `offset_chips`.
pub fn dll_chips(early: &Iq, late: &Iq, offset_chips: f32) -> f32 {
    let (e, l) = (early.magnitude(), late.magnitude());
    if !(e + l > 0.0) {
        return 0.0;
    }
    (1.0 - offset_chips) * (e - l) / (e + l)
}

/// 3rd-order PLL with 2nd-order FLL assist (Kaplan & Hegarty, §8.8), in Hz and cycles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CarrierLoop {
    /// Frequency-rate integrator, Hz/s.
    rate: f32,
    /// Frequency integrator, Hz (the Doppler estimate).
    frequency: f32,
}

impl CarrierLoop {
    /// A loop at `doppler_hz` with zero frequency rate.
    pub fn new(doppler_hz: f32) -> Self {
        Self {
            rate: 0.0,
            frequency: doppler_hz,
        }
    }

    /// A loop at `doppler_hz` with frequency rate `rate_hz_s` (Doppler-rate aiding).
    pub fn with_rate(doppler_hz: f32, rate_hz_s: f32) -> Self {
        Self {
            rate: rate_hz_s,
            frequency: doppler_hz,
        }
    }

    /// The Doppler estimate, Hz.
    pub fn frequency_hz(&self) -> f32 {
        self.frequency
    }

    /// The Doppler-rate estimate, Hz/s.
    pub fn rate_hz_s(&self) -> f32 {
        self.rate
    }

    /// One update with phase error `phase_cycles` (Costas) and frequency error `freq_hz`
    /// (FLL) over `t` seconds, PLL noise bandwidth `pll_bw` and FLL bandwidth `fll_bw` (Hz; 0
    /// switches a branch off). Returns the NCO frequency (Doppler) for the next interval, Hz:
    ///
    /// ```text
    /// ω_p = B_p/0.7845, ω_f = B_f/0.53, a₃ = 1.1, b₃ = 2.4, a₂ = √2
    /// r'  = r + T (ω_p³ e_φ + ω_f² e_f)
    /// f'  = f + T ((r + r')/2 + a₃ ω_p² e_φ + a₂ ω_f e_f)
    /// out = (f + f')/2 + b₃ ω_p e_φ
    /// ```
    pub fn update(
        &mut self,
        phase_cycles: f32,
        freq_hz: f32,
        t: f32,
        pll_bw: f32,
        fll_bw: f32,
    ) -> f32 {
        let wp = pll_bw / 0.7845;
        let wf = fll_bw / 0.53;
        let rate = self.rate + t * (wp * wp * wp * phase_cycles + wf * wf * freq_hz);
        let frequency = self.frequency
            + t * (0.5 * (self.rate + rate)
                + 1.1 * wp * wp * phase_cycles
                + core::f32::consts::SQRT_2 * wf * freq_hz);
        let out = 0.5 * (self.frequency + frequency) + 2.4 * wp * phase_cycles;
        if rate.is_finite() && frequency.is_finite() && out.is_finite() {
            self.rate = rate;
            self.frequency = frequency;
            out
        } else {
            self.frequency
        }
    }
}

/// The 1st-order DLL's code-rate correction, chips/s, for a code error in chips:
/// `4 B_L · e` (a 1st-order loop has `B_L = ω₀/4`).
pub fn dll_correction(error_chips: f32, bandwidth_hz: f32) -> f32 {
    4.0 * bandwidth_hz * error_chips
}
