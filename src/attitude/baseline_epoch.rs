//! The inputs of the baseline filters: one epoch of baseline vectors and velocity differences
//! in the reference frame (paper 000, eqs. (1), (6)–(9)). The antenna array in body axes is the
//! crate's shared [`AntennaArray`](super::array::AntennaArray); its errors convert into [`DcmError`] (`From<ArrayError>`:
//! coincident antennas → [`DcmError::ZeroLengthBaseline`]).

use nalgebra::Vector3;

use crate::attitude::dcm_filter::DcmError;
use crate::{real, Real};

use super::array::{BaselinePair, MIN_BASELINE_LENGTH};

/// One epoch of measurements, in the reference frame (ECEF for paper 000), indexed by
/// [`BaselinePair::index`]; `None` marks a pair whose antennas have no solution.
///
/// Timing: the filters step from `t_{k−1}` to `t_k = t_{k−1} + Δt`. The velocity differences
/// are the **mean over that step** (a receiver's accumulated Doppler, or carrier-phase change,
/// divided by `Δt`: the central difference for the middle of the step); the baselines are
/// measured **at `t_k`**.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BaselineEpoch<T = f32> {
    /// Measured baselines `r_i − r_j` at the end of the step, reference frame, metres
    /// (`ξ_ij, η_ij, ζ_ij` of eq. (8)).
    pub baselines: [Option<Vector3<T>>; 3],
    /// Measured velocity differences `V_i − V_j` over the step, reference frame, m/s (`V̂` of
    /// eq. (6)).
    pub velocity_differences: [Option<Vector3<T>>; 3],
}

impl<T: Real> BaselineEpoch<T> {
    /// An epoch from per-antenna solutions (reference frame: positions in metres, velocities in
    /// m/s, `None` for an antenna without a solution). A pair gets a baseline (a velocity
    /// difference) only if both of its antennas have a position (a velocity).
    pub fn from_antennas(
        positions: &[Option<Vector3<T>>; 3],
        velocities: &[Option<Vector3<T>>; 3],
    ) -> Self {
        let diff = |v: &[Option<Vector3<T>>; 3], pair: BaselinePair| {
            let (i, j) = pair.antennas();
            match (v.get(i).copied().flatten(), v.get(j).copied().flatten()) {
                (Some(a), Some(b)) => Some(a - b),
                _ => None,
            }
        };
        Self {
            baselines: BaselinePair::ALL.map(|p| diff(positions, p)),
            velocity_differences: BaselinePair::ALL.map(|p| diff(velocities, p)),
        }
    }

    /// The measured baseline of a pair, reference frame, metres.
    ///
    /// # Errors
    /// [`DcmError::MissingBaseline`], [`DcmError::NonFinite`], or
    /// [`DcmError::ZeroLengthBaseline`] when it is shorter than [`MIN_BASELINE_LENGTH`].
    pub fn baseline(&self, pair: BaselinePair) -> Result<Vector3<T>, DcmError> {
        let b = self
            .baselines
            .get(pair.index())
            .copied()
            .flatten()
            .ok_or(DcmError::MissingBaseline)?;
        if !b.iter().all(|v| v.is_finite()) {
            return Err(DcmError::NonFinite);
        }
        if !(b.norm() >= real(MIN_BASELINE_LENGTH)) {
            return Err(DcmError::ZeroLengthBaseline);
        }
        Ok(b)
    }

    /// The measured velocity difference of a pair, reference frame, m/s.
    ///
    /// # Errors
    /// [`DcmError::MissingBaseline`] or [`DcmError::NonFinite`].
    pub fn velocity_difference(&self, pair: BaselinePair) -> Result<Vector3<T>, DcmError> {
        let v = self
            .velocity_differences
            .get(pair.index())
            .copied()
            .flatten()
            .ok_or(DcmError::MissingBaseline)?;
        if !v.iter().all(|x| x.is_finite()) {
            return Err(DcmError::NonFinite);
        }
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::array::AntennaArray;

    #[test]
    fn coincident_antennas_and_missing_antennas_are_typed_errors() {
        let p = Vector3::new(0.1f32, 0.2, 0.3);
        assert_eq!(
            AntennaArray::new([p, p, Vector3::zeros()]).map_err(DcmError::from),
            Err(DcmError::ZeroLengthBaseline)
        );
        let epoch = BaselineEpoch::from_antennas(
            &[Some(p), Some(Vector3::zeros()), None],
            &[Some(p), Some(p), Some(p)],
        );
        assert!(epoch.baseline(BaselinePair::P12).is_ok());
        assert_eq!(
            epoch.baseline(BaselinePair::P23),
            Err(DcmError::MissingBaseline)
        );
        assert_eq!(
            epoch.velocity_difference(BaselinePair::P13).unwrap(),
            Vector3::zeros()
        );
        let mut bad = epoch;
        bad.baselines[0] = Some(Vector3::new(f32::NAN, 0.0, 0.0));
        assert_eq!(bad.baseline(BaselinePair::P12), Err(DcmError::NonFinite));
        bad.baselines[0] = Some(Vector3::zeros());
        assert_eq!(
            bad.baseline(BaselinePair::P12),
            Err(DcmError::ZeroLengthBaseline)
        );
    }
}
