//! The inputs of the baseline filters: the antenna array in body axes and one epoch of baseline
//! vectors and velocity differences in the reference frame (paper 000, eqs. (1), (6)–(9)).

use nalgebra::Vector3;

use crate::error::DcmError;
use crate::{real, Real};

/// Shortest baseline the filters accept, metres. Shorter body baselines (antennas at the same
/// place) and shorter measured baselines (a receiver reporting the same position for two
/// antennas) are rejected with [`DcmError::ZeroLengthBaseline`].
pub const MIN_BASELINE_LENGTH: f64 = 1e-3;

/// One of the three antenna pairs of a three-antenna array. The baseline of pair `ij` is
/// `b_ij = r_i − r_j` (paper 000, eq. (1)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BaselinePair {
    /// Antennas 1 and 2: `b₁₂ = r₁ − r₂`.
    P12,
    /// Antennas 2 and 3: `b₂₃ = r₂ − r₃`.
    P23,
    /// Antennas 1 and 3: `b₁₃ = r₁ − r₃ = b₁₂ + b₂₃`.
    P13,
}

impl BaselinePair {
    /// The three pairs, in the order of the arrays of [`BaselineEpoch`].
    pub const ALL: [Self; 3] = [Self::P12, Self::P23, Self::P13];

    /// Index of the pair in the arrays of [`BaselineEpoch`] (0, 1, 2).
    pub fn index(self) -> usize {
        match self {
            Self::P12 => 0,
            Self::P23 => 1,
            Self::P13 => 2,
        }
    }

    /// The two antennas (0-based) `(i, j)` of `b_ij = r_i − r_j`.
    pub fn antennas(self) -> (usize, usize) {
        match self {
            Self::P12 => (0, 1),
            Self::P23 => (1, 2),
            Self::P13 => (0, 2),
        }
    }
}

/// The three antenna phase centres in body axes, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AntennaArray<T = f32> {
    positions: [Vector3<T>; 3],
}

impl<T: Real> AntennaArray<T> {
    /// An array from the antenna positions `r₁, r₂, r₃` in body axes, metres.
    ///
    /// # Errors
    /// [`DcmError::NonFinite`] for a non-finite coordinate; [`DcmError::ZeroLengthBaseline`]
    /// when two antennas are closer than [`MIN_BASELINE_LENGTH`].
    pub fn new(positions: [Vector3<T>; 3]) -> Result<Self, DcmError> {
        if !positions.iter().all(|p| p.iter().all(|v| v.is_finite())) {
            return Err(DcmError::NonFinite);
        }
        let array = Self { positions };
        for pair in BaselinePair::ALL {
            if !(array.baseline(pair).norm() >= real(MIN_BASELINE_LENGTH)) {
                return Err(DcmError::ZeroLengthBaseline);
            }
        }
        Ok(array)
    }

    /// The array with antenna 1 at the body origin and the baselines `b₁₂`, `b₂₃` (body axes,
    /// metres), as paper 000 specifies it.
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn from_baselines(b12: &Vector3<T>, b23: &Vector3<T>) -> Result<Self, DcmError> {
        let r1 = Vector3::zeros();
        let r2 = r1 - b12;
        let r3 = r2 - b23;
        Self::new([r1, r2, r3])
    }

    /// The antenna positions in body axes, metres.
    pub fn positions(&self) -> &[Vector3<T>; 3] {
        &self.positions
    }

    /// The baseline `b_ij = r_i − r_j` of a pair in body axes, metres.
    pub fn baseline(&self, pair: BaselinePair) -> Vector3<T> {
        let (i, j) = pair.antennas();
        match (self.positions.get(i), self.positions.get(j)) {
            (Some(a), Some(b)) => a - b,
            _ => Vector3::zeros(),
        }
    }
}

/// One epoch of measurements, in the reference frame (ECEF for paper 000), indexed by
/// [`BaselinePair::index`]; `None` marks a pair whose antennas have no solution.
///
/// Timing: the filters step from `t_{k−1}` to `t_k = t_{k−1} + Δt`. The velocity differences
/// are the **mean over that step** (a receiver's accumulated Doppler, or carrier-phase change,
/// divided by `Δt`: the central difference for the middle of the step); the baselines are
/// measured **at `t_k`**.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
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

    #[test]
    fn baselines_are_position_differences_and_b13_is_their_sum() {
        let b12 = Vector3::new(1.5, 1.8, 1.9);
        let b23 = Vector3::new(1.7, 1.7, 2.0);
        let array = AntennaArray::<f64>::from_baselines(&b12, &b23).unwrap();
        assert!((array.baseline(BaselinePair::P12) - b12).norm() < 1e-15);
        assert!((array.baseline(BaselinePair::P23) - b23).norm() < 1e-15);
        assert!((array.baseline(BaselinePair::P13) - (b12 + b23)).norm() < 1e-15);
    }

    #[test]
    fn coincident_antennas_and_missing_antennas_are_typed_errors() {
        let p = Vector3::new(0.1f32, 0.2, 0.3);
        assert_eq!(
            AntennaArray::new([p, p, Vector3::zeros()]),
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
