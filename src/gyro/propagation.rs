//! Attitude propagation from gyro increments, paper eq. (1.1): `Ṁ = ½ M ∘ ω*`.
//!
//! The gyro delivers, every sample interval `h`, the increment `θ_k = ∫_{t_{k−1}}^{t_k} ω* dt`
//! (rad, gyro axes): either as a float ([`AttitudePropagator::push`]) or as counts of pulses of
//! weight `σ` ([`PulseDecoder`]). The propagator pairs the samples and advances the quaternion
//! over `H = 2h` by the two-sample coning-corrected rotation vector
//! `φ = θ₁ + θ₂ + ⅔ θ₁ × θ₂`, `M ← M ∘ exp(φ)`, whose local error is `O(H⁵)` (the paper asks
//! for `O(H⁵)`); it is exact for a rate that is constant over the step.

use nalgebra::Vector3;

use crate::geometry::Quaternion;
use crate::gyro::CalibrationError;
use crate::{real, Real};

/// The two-sample coning-corrected rotation vector over `H = 2h` from the increments of its two
/// halves (rad, body axes): `φ = θ₁ + θ₂ + ⅔ θ₁ × θ₂`.
pub fn two_sample_rotation_vector<T: Real>(theta1: &Vector3<T>, theta2: &Vector3<T>) -> Vector3<T> {
    theta1 + theta2 + theta1.cross(theta2) * real::<T>(2.0 / 3.0)
}

/// What one completed propagation step did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PropagationStep<T = f32> {
    /// Sum of the two increments of the step, `θ₁ + θ₂` (rad, gyro axes).
    pub increment: Vector3<T>,
    /// The coning-corrected rotation vector applied (rad, gyro axes).
    pub rotation_vector: Vector3<T>,
}

/// The computed attitude `M` (gyro axes to the computed frame `K`, Hamilton, `q_KE`),
/// advanced by pairs of gyro increments.
///
/// `M` is kept as `M_a ∘ Δ`: an anchor `M_a` and the rotation `Δ` since the anchor, into which
/// the steps are composed. `Δ` stays within [`FOLD_ANGLE`] of the identity, where the
/// rounding of its vector part is `ε |Δ|` instead of `ε`; it is folded into the anchor only
/// every [`FOLD_ANGLE`] of rotation. In `f32` this makes the propagated attitude about ten
/// times more accurate than composing every step into `M` (whose components are `O(1)`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AttitudePropagator<T = f32> {
    anchor: Quaternion<T>,
    delta: Quaternion<T>,
    pending: Option<Vector3<T>>,
}

/// Rotation (rad) accumulated in the near-identity part of [`AttitudePropagator`] before it is
/// folded into the anchor.
pub const FOLD_ANGLE: f64 = 0.125;

impl<T: Real> AttitudePropagator<T> {
    /// A propagator at the attitude `m0` (normalized here).
    ///
    /// # Errors
    /// [`CalibrationError::NonFiniteInput`], or [`CalibrationError::InputOutOfRange`] for a
    /// quaternion of (near) zero norm.
    pub fn new(m0: Quaternion<T>) -> Result<Self, CalibrationError> {
        if !m0.is_finite() {
            return Err(CalibrationError::NonFiniteInput);
        }
        // (finite, checked above: a refusal can only be a zero norm, which this variant names)
        let q = m0
            .normalize()
            .map_err(|_| CalibrationError::InputOutOfRange)?;
        Ok(Self {
            anchor: q,
            delta: Quaternion::identity(),
            pending: None,
        })
    }

    /// The computed attitude `M` at the last completed step.
    pub fn attitude(&self) -> Quaternion<T> {
        let m = self.anchor * self.delta;
        m.normalize().unwrap_or(m)
    }

    /// True when the first sample of a step is waiting for its second.
    pub fn mid_step(&self) -> bool {
        self.pending.is_some()
    }

    /// Takes one increment `θ` (rad, gyro axes, over `h`). Every second call completes a step
    /// `H = 2h` and returns what it did.
    ///
    /// # Errors
    /// [`CalibrationError::NonFiniteInput`]; [`CalibrationError::InputOutOfRange`] for an
    /// increment above 1 rad (the two-sample formula needs small increments). The propagator
    /// is then unchanged.
    pub fn push(
        &mut self,
        theta: &Vector3<T>,
    ) -> Result<Option<PropagationStep<T>>, CalibrationError> {
        check_increment(theta)?;
        match self.pending.take() {
            None => {
                self.pending = Some(*theta);
                Ok(None)
            }
            Some(first) => {
                let phi = two_sample_rotation_vector(&first, theta);
                // eq. (1.1) over H: M(t + H) = M(t) ∘ exp(φ), i.e. Δ ← Δ ∘ exp(φ), renormalized
                let next = self.delta * Quaternion::from_rotation_vector(&phi);
                self.delta = next.normalize().unwrap_or(next);
                // sin²(FOLD_ANGLE / 2) ≈ (FOLD_ANGLE / 2)²
                let fold = real::<T>(FOLD_ANGLE * FOLD_ANGLE / 4.0);
                if self.delta.vector().norm_squared() > fold {
                    self.anchor = self.attitude();
                    self.delta = Quaternion::identity();
                }
                Ok(Some(PropagationStep {
                    increment: first + theta,
                    rotation_vector: phi,
                }))
            }
        }
    }
}

fn check_increment<T: Real>(theta: &Vector3<T>) -> Result<(), CalibrationError> {
    if !theta.iter().all(|v| v.is_finite()) {
        return Err(CalibrationError::NonFiniteInput);
    }
    if theta.iter().any(|v| v.abs() > T::one()) {
        return Err(CalibrationError::InputOutOfRange);
    }
    Ok(())
}

/// How the quantization residual of pulse-counting gyros is centred (paper §5).
///
/// A pulse of weight `σ` is emitted each time the integral of `ω*ᵢ` since the last pulse
/// reaches `±σ`, so the counted increments lag the true ones by the residual `Δθ`, uniform on
/// `[0, σ)` (or `(−σ, 0]`) with mean `½ σ sign ω*`: the computed attitude lags by
/// `q_F = −½ Δθ` (corrected eq. (5.2)), a bias of the equations that degrades the biases'
/// estimates about tenfold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResidualCentering {
    /// No centering (the paper's second case).
    #[default]
    None,
    /// Eq. (5.5): the mean residual is added to each equation's right-hand side,
    /// `z' = p' − p + ¼ σ [p₀E₃ − Φ(p)] Bᵀ ρ*`, `ρ* = sign θ*_k` of the last sample.
    MeanResidual,
    /// Eq. (5.6): each increment is corrected before integration,
    /// `θ°ᵢ,ₖ = θ*ᵢ,ₖ + ½ σ (sign θ*ᵢ,ₖ − sign θ*ᵢ,ₖ₋₁)`, `sign θ*ᵢ,₀ = 0`; by telescoping the
    /// integrated attitude carries the mean residual.
    IncrementCorrection,
}

/// Converts pulse counts of weight `σ` into increments, with the centering of eq. (5.6) if
/// asked, and remembers the signs `ρ*` of the last sample for eq. (5.5).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PulseDecoder<T = f32> {
    sigma: T,
    centering: ResidualCentering,
    last_sign: [i8; 3],
}

impl<T: Real> PulseDecoder<T> {
    /// A decoder for pulses of weight `sigma` (rad).
    ///
    /// # Errors
    /// [`CalibrationError::InvalidConfig`] unless `sigma` is finite and positive.
    pub fn new(sigma: T, centering: ResidualCentering) -> Result<Self, CalibrationError> {
        if !(sigma.is_finite() && sigma > T::zero()) {
            return Err(CalibrationError::InvalidConfig);
        }
        Ok(Self {
            sigma,
            centering,
            last_sign: [0; 3],
        })
    }

    /// Pulse weight `σ` (rad).
    pub fn sigma(&self) -> T {
        self.sigma
    }

    /// The centering applied.
    pub fn centering(&self) -> ResidualCentering {
        self.centering
    }

    /// `ρ* = sign θ*_k` of the last decoded sample (−1, 0 or +1 per axis).
    pub fn last_signs(&self) -> [i8; 3] {
        self.last_sign
    }

    /// The increment (rad, gyro axes) of one sample of pulse counts `n` (signed, per axis):
    /// `θ* = n σ` (eq. (5.1)), plus the correction of eq. (5.6) when configured.
    ///
    /// # Errors
    /// [`CalibrationError::InputOutOfRange`] when `|n σ|` exceeds 1 rad; the decoder is then
    /// unchanged.
    pub fn decode(&mut self, counts: [i32; 3]) -> Result<Vector3<T>, CalibrationError> {
        let mut theta = Vector3::<T>::zeros();
        let mut sign = [0i8; 3];
        for i in 0..3 {
            let v = real::<T>(f64::from(counts[i])) * self.sigma;
            if !(v.abs() <= T::one()) {
                return Err(CalibrationError::InputOutOfRange);
            }
            sign[i] = counts[i].signum() as i8;
            theta[i] = v;
            if self.centering == ResidualCentering::IncrementCorrection {
                // eq. (5.6): θ° = θ* + ½ σ (sign θ*_k − sign θ*_{k−1})
                let ds = real::<T>(f64::from(sign[i]) - f64::from(self.last_sign[i]));
                theta[i] += real::<T>(0.5) * self.sigma * ds;
            }
        }
        self.last_sign = sign;
        Ok(theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_rate_is_integrated_exactly() {
        let w = Vector3::new(0.3, -0.2, 0.5);
        let h = 0.02;
        let mut p = AttitudePropagator::new(Quaternion::<f64>::identity()).unwrap();
        for _ in 0..500 {
            p.push(&(w * h)).unwrap();
        }
        let exact = Quaternion::from_rotation_vector(&(w * (500.0 * h)));
        assert!(p.attitude().angle_to(&exact) < 1e-12);
    }

    #[test]
    fn centering_5_6_telescopes_to_half_a_pulse() {
        let mut d = PulseDecoder::<f64>::new(1e-3, ResidualCentering::IncrementCorrection).unwrap();
        let mut sum = 0.0;
        for n in [3, 4, 3, -2, -3, 5] {
            sum += d.decode([n, 0, 0]).unwrap().x;
        }
        // Σθ° = Σθ* + ½ σ sign θ*_last
        assert!((sum - (10.0e-3 + 0.5e-3)).abs() < 1e-15);
        assert_eq!(d.last_signs(), [1, 0, 0]);
    }
}
