//! The two update forms of the one-stage filter: the Gaussian approximation of eqs. (9)–(12)
//! and the constant-gain loop of the paper's simulation.

use nalgebra::{SMatrix, SVector, Vector2, Vector3};

use crate::attitude::one_stage::OneStageError;
use crate::{real, Real};

use super::config::ProcessNoise;
use super::filter::OneStageFilter;
use super::information::{EpochInformation, PARAMETERS};
use super::layout::StateLayout;
use crate::linalg::{marginal_information, psd_factor, regularized_solve};

impl<T: Real, const N: usize> OneStageFilter<T, N> {
    /// Eqs. (11), (12), (9): `D̃ = F D Fᵀ + G D_ξ Gᵀ`, `D⁻¹ = D̃⁻¹ + cᵀ W c` with
    /// `W = −∂²F/∂θ∂θᵀ` (floored), `X̂ = X̃ + D cᵀ u`. The information update is done in
    /// covariance form with the toolkit's Joseph update: `W = L̃ L̃ᵀ`, pseudo-measurement
    /// rows `H = L̃ᵀ c` with unit noise, which gives exactly `(D̃⁻¹ + Hᵀ H)⁻¹`.
    pub(super) fn gaussian_update(
        &mut self,
        f: &SMatrix<T, N, N>,
        x_pred: &SVector<T, N>,
        info: &EpochInformation<T>,
    ) -> Result<(), OneStageError> {
        let q = self.process_noise(info);
        self.ekf.predict_to(x_pred, f, &q)?;
        if info.satellites == 0 {
            return Ok(());
        }
        let l = psd_factor(&info.observed);
        let h: SMatrix<T, PARAMETERS, N> = l.transpose() * self.layout.c;
        let ct_u = self.layout.c.transpose() * SVector::<T, PARAMETERS>::from(info.gradient);
        self.ekf.update(
            &SVector::<T, PARAMETERS>::zeros(),
            &h,
            &SMatrix::identity(),
            None,
        )?;
        // eq. (9): X̂ = X̃ + D_X cᵀ u
        let x = x_pred + self.ekf.covariance() * ct_u;
        Ok(self.ekf.set_state(x)?)
    }

    /// `G D_ξ Gᵀ` of eq. (11) for this epoch (see [`ProcessNoise`]).
    fn process_noise(&mut self, info: &EpochInformation<T>) -> SMatrix<T, N, N> {
        let t = self.config.epoch_s;
        let psd: [T; PARAMETERS] = match self.config.process_noise {
            ProcessNoise::Fixed {
                accel_psd,
                bias_psd,
            } => {
                let [qa, qb, qg] = accel_psd;
                [qa, qb, qg, bias_psd, bias_psd]
            }
            ProcessNoise::Bandwidth => {
                let wn = self.config.natural_frequency();
                let wb = self.config.bias_bandwidth_hz * real(4.0);
                // marginal information of each angle (biases known) and of each bias (all
                // else unknown), as the constant-gain loop's normalization sees them
                let angles = marginal_information(&info.expected_angles());
                let all = if self.config.line_bias_states {
                    marginal_information(&info.expected)
                } else {
                    SVector::zeros()
                };
                for (k, slot) in (0..self.scheduled_psd.len()).zip(self.scheduled_psd.iter_mut()) {
                    let j = if k < 3 { angles.get(k) } else { all.get(k) };
                    // information rate J / T, 1/rad²/s
                    let rate = j.copied().unwrap_or_else(T::zero) / t;
                    if rate > T::zero() && rate.is_finite() {
                        *slot = if k < 3 {
                            wn * wn * wn * wn / rate // q = ω_n⁴ / J
                        } else {
                            wb * wb / rate // q_b = (4 Δf_b)² / J
                        };
                    }
                }
                self.scheduled_psd
            }
        };
        // eq. (7): v_k = v_{k−1} + ξ for each estimated angle; the biases walk themselves
        let [qa, qb, qg, qbb, qbc] = psd.map(|q| q * t);
        StateLayout::spread(&self.layout.rates, &Vector3::new(qa, qb, qg))
            + StateLayout::spread(&self.layout.biases, &Vector2::new(qbb, qbc))
    }

    /// The constant-gain loop: `u_n = J_T⁻¹ u`, then `α̂ = α̃ + K1 u_n`, `v̂ = ṽ + K2 u_n`,
    /// `b̂ = b̃ + K_b u_{n,b}`. The angles' normalization is conditional on the biases
    /// (`J_αα⁻¹ u_α`, computed by the caller), the biases' is joint (`(J⁻¹u)_b`), so that the
    /// bias loop sees unit slope and the angle loop the noise of known biases.
    pub(super) fn constant_gain_update(
        &mut self,
        x_pred: &SVector<T, N>,
        info: &EpochInformation<T>,
        un_a: &Vector3<T>,
    ) -> Result<(), OneStageError> {
        let mut x = *x_pred;
        if info.satellites > 0 {
            let (k1, k2) = self.config.loop_gains();
            // (un_a is zero for angles that are not estimated: their information is masked)
            x += self.layout.angles.transpose() * (un_a * k1)
                + self.layout.rates.transpose() * (un_a * k2);
            if self.config.line_bias_states {
                let kb = self.config.bias_gain();
                let gradient = SVector::<T, PARAMETERS>::from(info.gradient);
                let un = regularized_solve(&info.expected, &gradient);
                x += self.layout.biases.transpose() * (Vector2::new(un[3], un[4]) * kb);
            }
        }
        Ok(self.ekf.set_state(x)?)
    }
}
