//! Cold start: the inter-antenna carrier-phase single differences of one satellite, averaged
//! over a few hundred epochs of the same [`SatelliteObservation`]s the filter takes, in the
//! form of the snapshot solver's [`PhaseSatellite`] (paper 002). The receiver resolves the
//! ambiguities with [`AmbiguityResolver`](crate::attitude::ambiguity::AmbiguityResolver) and
//! starts the one-stage filter from [`Prior::from_snapshot`](super::Prior::from_snapshot).
//!
//! # Model
//!
//! With `z_P ∝ d e^{j(φ + ψ_P + b_P)} + n_P` in noise units, the product `z_P z_A*` is free of
//! the data bit `d` and of the common phase `φ`; its mean over `n` epochs has the phase
//! `ψ_P − ψ_A + b_P − b_A`. In the snapshot solver's convention (phase counted as a range,
//! `Φ_A − Φ_P`, baselines `b_i = r_i − r_A`), `ψ_P − ψ_A = 2π μᵀ C_rb (r_P − r_A)/λ` is
//! `2π (Φ_A − Φ_P)`: the single difference of baseline `i` (B, then C) is
//! `arg Σ z_P z_A* / 2π` cycles, line biases included (remove calibrated ones first). Its
//! standard deviation at high SNR is `σ = 1/(2π √(q_T n))` cycles (each antenna's phase noise
//! `1/√(2 q_T n)` rad, two antennas).
//!
//! The slaved antennas share the reference antenna's code NCO, so there is no per-antenna code
//! measurement: [`PhaseDifferences::phase_satellite`] sets the code single differences to zero,
//! and the resolver's `code_sigma_m` must then be at least the longest baseline, so that the
//! array's geometry (baseline lengths and angle, the constrained search) fixes the integers.
//! The float covariance is then some 10⁷ times wider along the code directions than along the
//! phases: run the resolver in `f64` (a one-off at a cold start; `tests/one_stage_samples.rs`
//! does so on synthesized samples), where `f32` reports it as not positive definite.

use nalgebra::{Complex, Vector3};

use crate::attitude::one_stage::OneStageError;
use crate::attitude::range_model::PhaseSatellite;

use super::input::SatelliteObservation;

/// The averaged single differences of one satellite (antennas B and C against A).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PhaseDifferences {
    id: u8,
    los: [f32; 3],
    /// `Σ z_B z_A*`, `Σ z_C z_A*` (noise units).
    sum: [Complex<f32>; 2],
    /// `Σ 10^(C/N0 / 10)`, Hz.
    cn0_sum: f32,
    epochs: u32,
}

/// Summarised on purpose: the sums as `(re, im)` pairs (num-complex has no defmt support).
#[cfg(feature = "defmt")]
impl defmt::Format for PhaseDifferences {
    fn format(&self, f: defmt::Formatter<'_>) {
        let [b, c] = self.sum;
        defmt::write!(
            f,
            "PhaseDifferences {{ id: {=u8}, epochs: {=u32}, B: ({=f32}, {=f32}), C: ({=f32}, {=f32}) }}",
            self.id,
            self.epochs,
            b.re,
            b.im,
            c.re,
            c.im
        );
    }
}

impl PhaseDifferences {
    /// An empty average.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one epoch of the satellite (the first one sets the satellite; its line of sight is
    /// the latest one's).
    ///
    /// # Errors
    /// [`OneStageError::InvalidObservation`] for another satellite's observation or a noise
    /// variance that is not positive; [`OneStageError::NonFiniteInput`]. Unchanged on error.
    pub fn add(&mut self, obs: &SatelliteObservation<f32>) -> Result<(), OneStageError> {
        if self.epochs > 0 && obs.id != self.id {
            return Err(OneStageError::InvalidObservation);
        }
        let values = obs.prompt.i.iter().chain(obs.prompt.q.iter());
        if !values.chain(obs.los.iter()).all(|v| v.is_finite())
            || !obs.noise_var.is_finite()
            || !obs.cn0_dbhz.is_finite()
        {
            return Err(OneStageError::NonFiniteInput);
        }
        if !(obs.noise_var > 0.0) {
            return Err(OneStageError::InvalidObservation);
        }
        let [za, zb, zc] = obs.prompt.normalized(crate::sqrtf(obs.noise_var));
        let [sb, sc] = self.sum;
        self.sum = [sb + zb * za.conj(), sc + zc * za.conj()];
        self.cn0_sum += libm::powf(10.0, 0.1 * obs.cn0_dbhz);
        self.id = obs.id;
        self.los = obs.los;
        self.epochs = self.epochs.saturating_add(1);
        Ok(())
    }

    /// Epochs averaged.
    pub fn epochs(&self) -> u32 {
        self.epochs
    }

    /// The single differences `Φ_A − Φ_B`, `Φ_A − Φ_C` (range sense, see the module docs),
    /// cycles in `(−½, ½]`; `None` before the first epoch.
    pub fn phase_cycles(&self) -> Option<[f32; 2]> {
        if self.epochs == 0 {
            return None;
        }
        let inv_two_pi = 0.5 * core::f32::consts::FRAC_1_PI;
        Some(self.sum.map(|s| libm::atan2f(s.im, s.re) * inv_two_pi))
    }

    /// Standard deviation of one single difference, cycles: `1/(2π √(q_T n))` with the mean
    /// C/N0 and `q_T = (C/N0)·epoch_s`; `None` before the first epoch.
    pub fn sigma_cycles(&self, epoch_s: f32) -> Option<f32> {
        if self.epochs == 0 || !(epoch_s > 0.0) {
            return None;
        }
        let q_n = self.cn0_sum * epoch_s; // Σ q_T = q_T n
        Some(0.5 * core::f32::consts::FRAC_1_PI / crate::sqrtf(q_n))
    }

    /// The average as the snapshot solver's input (two baselines, A→B and A→C): phases from
    /// [`Self::phase_cycles`], zero code, and the cofactor `(σ/sigma_ref_cycles)²` (σ from
    /// [`Self::sigma_cycles`]; pass the σ the resolver is configured with, in cycles).
    pub fn phase_satellite(
        &self,
        epoch_s: f32,
        sigma_ref_cycles: f32,
    ) -> Option<PhaseSatellite<2, f32>> {
        let phase_cycles = self.phase_cycles()?;
        let sigma = self.sigma_cycles(epoch_s)?;
        let cofactor = (sigma / sigma_ref_cycles) * (sigma / sigma_ref_cycles);
        if !(cofactor.is_finite() && cofactor > 0.0) {
            return None;
        }
        Some(PhaseSatellite {
            id: self.id,
            los: Vector3::from(self.los),
            phase_cycles,
            code_m: [0.0; 2],
            cofactor,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::one_stage::PromptIq;

    fn obs(id: u8, phases: [f32; 3], bit: f32) -> SatelliteObservation<f32> {
        let mut prompt = PromptIq::default();
        for (p, phase) in phases.iter().enumerate() {
            prompt.i[p] = 20.0 * bit * libm::cosf(*phase);
            prompt.q[p] = 20.0 * bit * libm::sinf(*phase);
        }
        SatelliteObservation {
            id,
            los: [0.0, 0.0, 1.0],
            prompt,
            noise_var: 4.0,
            cn0_dbhz: 40.0,
        }
    }

    #[test]
    fn single_differences_ignore_the_bit_and_the_common_phase() {
        let mut d = PhaseDifferences::new();
        assert_eq!(d.phase_cycles(), None);
        for k in 0..10 {
            let common = 0.7 * k as f32;
            let bit = if k % 3 == 0 { -1.0 } else { 1.0 };
            d.add(&obs(3, [common, common + 0.5, common - 2.0], bit))
                .unwrap();
        }
        let [b, c] = d.phase_cycles().unwrap();
        let two_pi = core::f32::consts::TAU;
        assert!((b - 0.5 / two_pi).abs() < 1e-5, "{b}");
        assert!((c + 2.0 / two_pi).abs() < 1e-5, "{c}");
        // 40 dB-Hz, 1 ms, 10 epochs: 1/(2π √100)
        let s = d.sigma_cycles(1e-3).unwrap();
        assert!((s - 1.0 / (two_pi * 10.0)).abs() < 1e-5);
        let sat = d.phase_satellite(1e-3, s).unwrap();
        assert!((sat.cofactor - 1.0).abs() < 1e-4);
        assert_eq!(sat.id, 3);
        let before = d;
        assert_eq!(
            d.add(&obs(4, [0.0; 3], 1.0)),
            Err(OneStageError::InvalidObservation)
        );
        let mut nan = obs(3, [0.0; 3], 1.0);
        nan.prompt.q[1] = f32::NAN;
        assert_eq!(d.add(&nan), Err(OneStageError::NonFiniteInput));
        assert_eq!(d, before);
    }
}
