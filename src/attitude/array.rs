//! The three-antenna array in body axes, shared by every estimator of the crate: the baseline
//! filters of paper 000 ([`super::dcm_filter`], [`super::multi_structure`],
//! [`super::rigid_body`]), the one-stage filter of paper 003 ([`super::one_stage`]) and the
//! receiver built on them.
//!
//! The antennas are called A, B, C ([`Antenna`]; paper 003's names) or 1, 2, 3 (paper 000's);
//! antenna A = 1 is the reference antenna of the signal chain (correlator input 0). Baselines
//! follow paper 000: `b_ij = r_i − r_j` ([`BaselinePair`]).
//!
//! Validation is shared: [`AntennaArray::new`] accepts any three finite positions whose
//! pairwise distances are at least [`MIN_BASELINE_LENGTH`]; an estimator that needs the
//! antennas to span a plane (the one-stage filter: the rotation about a line through three
//! collinear antennas is unobservable) checks [`AntennaArray::check_spans_plane`] when it is
//! built.

use nalgebra::Vector3;

use crate::error::{Error, ErrorKind};
use crate::{real, Real};

/// Shortest distance between two antennas the array accepts, metres (also the shortest
/// measured baseline the paper-000 filters accept).
pub const MIN_BASELINE_LENGTH: f64 = 1e-3;

/// Smallest ratio of the triangle's doubled area to its longest side squared for which the
/// antennas count as spanning a plane ([`AntennaArray::check_spans_plane`]).
pub const MIN_SHAPE_RATIO: f64 = 2e-6;

/// One antenna of the array, in the order of paper 003: A, B, C (paper 000's 1, 2, 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Antenna {
    /// Antenna A (index 0, paper 000's antenna 1, the signal chain's reference antenna).
    A,
    /// Antenna B (index 1, paper 000's antenna 2).
    B,
    /// Antenna C (index 2, paper 000's antenna 3).
    C,
}

impl Antenna {
    /// The three antennas in index order.
    pub const ALL: [Self; 3] = [Self::A, Self::B, Self::C];

    /// Index of the antenna (0, 1, 2).
    pub fn index(self) -> usize {
        match self {
            Self::A => 0,
            Self::B => 1,
            Self::C => 2,
        }
    }
}

/// One of the three antenna pairs. The baseline of pair `ij` is `b_ij = r_i − r_j` (paper 000,
/// eq. (1)).
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
    /// The three pairs, in the order of the arrays of
    /// [`BaselineEpoch`](super::baseline_epoch::BaselineEpoch).
    pub const ALL: [Self; 3] = [Self::P12, Self::P23, Self::P13];

    /// Index of the pair in the arrays of
    /// [`BaselineEpoch`](super::baseline_epoch::BaselineEpoch) (0, 1, 2).
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

/// The phase centres of antennas A, B, C (paper 000's `r₁, r₂, r₃`) relative to the body
/// origin, in body axes, metres. For paper 003 the origin is the triangle's `O_c` and the
/// positions are its `r_P = L_{PO_c} 1_{PO_c,c}` of eq. (4); the one-stage attitude estimate
/// does not depend on the choice of origin (the common carrier phase is averaged out), only
/// the filter's internal phases do.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AntennaArray<T = f32> {
    positions: [Vector3<T>; 3],
}

impl<T: Real> AntennaArray<T> {
    /// An array from the positions of A, B, C (`r₁, r₂, r₃`) in body axes, metres.
    ///
    /// # Errors
    /// [`ArrayError::NonFinite`] for a non-finite coordinate; [`ArrayError::CoincidentAntennas`]
    /// when two antennas are closer than [`MIN_BASELINE_LENGTH`].
    pub fn new(positions: [Vector3<T>; 3]) -> Result<Self, ArrayError> {
        if !positions.iter().all(|p| p.iter().all(|v| v.is_finite())) {
            return Err(ArrayError::NonFinite);
        }
        let array = Self { positions };
        for pair in BaselinePair::ALL {
            if !(array.baseline(pair).norm() >= real(MIN_BASELINE_LENGTH)) {
                return Err(ArrayError::CoincidentAntennas);
            }
        }
        Ok(array)
    }

    /// The array with antenna 1 (A) at the body origin and the baselines `b₁₂`, `b₂₃` (body
    /// axes, metres), as paper 000 specifies it.
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn from_baselines(b12: &Vector3<T>, b23: &Vector3<T>) -> Result<Self, ArrayError> {
        let r1 = Vector3::zeros();
        let r2 = r1 - b12;
        let r3 = r2 - b23;
        Self::new([r1, r2, r3])
    }

    /// The array of paper 003's simulation: an equilateral triangle of side `side_m` metres
    /// with `O_c` at the middle of AB, `X_c` pointing to B and `Y_c` to C (spec erratum 9):
    /// `A = (−l/2, 0, 0)`, `B = (l/2, 0, 0)`, `C = (0, l√3/2, 0)`. C then lies on the `Y_c`
    /// axis, so a rotation about `Y_c` moves only A and B.
    ///
    /// # Errors
    /// [`ArrayError::NonFinite`] for a non-finite side, [`ArrayError::CoincidentAntennas`] for
    /// a side shorter than [`MIN_BASELINE_LENGTH`] (or negative).
    pub fn paper_triangle(side_m: T) -> Result<Self, ArrayError> {
        if !side_m.is_finite() {
            return Err(ArrayError::NonFinite);
        }
        if !(side_m >= real(MIN_BASELINE_LENGTH)) {
            return Err(ArrayError::CoincidentAntennas);
        }
        let half = side_m * real(0.5);
        let height = side_m * real::<T>(0.75).sqrt();
        let o = T::zero();
        Self::new([
            Vector3::new(-half, o, o),
            Vector3::new(half, o, o),
            Vector3::new(o, height, o),
        ])
    }

    /// Positions of A, B, C (`r₁, r₂, r₃`) in body axes, metres.
    pub fn positions(&self) -> &[Vector3<T>; 3] {
        &self.positions
    }

    /// Position of one antenna in body axes, metres.
    pub fn position(&self, antenna: Antenna) -> Vector3<T> {
        let [a, b, c] = self.positions;
        match antenna {
            Antenna::A => a,
            Antenna::B => b,
            Antenna::C => c,
        }
    }

    /// The baseline `b_ij = r_i − r_j` of a pair in body axes, metres.
    pub fn baseline(&self, pair: BaselinePair) -> Vector3<T> {
        let (i, j) = pair.antennas();
        match (self.positions.get(i), self.positions.get(j)) {
            (Some(a), Some(b)) => a - b,
            _ => Vector3::zeros(),
        }
    }

    /// Checks that the antennas span a plane: the triangle's doubled area is at least
    /// [`MIN_SHAPE_RATIO`] times its longest side squared.
    ///
    /// # Errors
    /// [`ArrayError::CollinearAntennas`].
    pub fn check_spans_plane(&self) -> Result<(), ArrayError> {
        let [a, b, c] = self.positions;
        let (ab, ac, bc) = (b - a, c - a, c - b);
        let longest = ab.norm().max(ac.norm()).max(bc.norm());
        let twice_area = ab.cross(&ac).norm();
        if twice_area >= real::<T>(MIN_SHAPE_RATIO) * longest * longest {
            Ok(())
        } else {
            Err(ArrayError::CollinearAntennas)
        }
    }
}

/// Errors of the antenna array ([`crate::attitude::array::AntennaArray`]), shared by the
/// paper-000 filters and the one-stage filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ArrayError {
    /// An antenna coordinate or the side of the triangle was NaN or infinite.
    #[error("non-finite antenna position")]
    NonFinite,
    /// Two antennas are closer than
    /// [`MIN_BASELINE_LENGTH`] (or a triangle
    /// side is shorter than that, or negative).
    #[error("two antennas (nearly) coincide")]
    CoincidentAntennas,
    /// The three antennas are (nearly) collinear: they span no plane, so the rotation about
    /// their line is unobservable (checked by the estimators that need a plane).
    #[error("the three antennas are (nearly) collinear")]
    CollinearAntennas,
}

impl Error for ArrayError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::CoincidentAntennas | Self::CollinearAntennas => ErrorKind::InvalidInput,
        }
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
        assert!(array.check_spans_plane().is_ok());
        for (k, antenna) in Antenna::ALL.into_iter().enumerate() {
            assert_eq!(antenna.index(), k);
            assert_eq!(array.position(antenna), array.positions()[k]);
        }
    }

    #[test]
    fn paper_triangle_is_equilateral_with_c_on_the_y_axis() {
        let arr = AntennaArray::<f64>::paper_triangle(1.5).unwrap();
        let [a, b, c] = *arr.positions();
        for d in [(b - a).norm(), (c - a).norm(), (c - b).norm()] {
            assert!((d - 1.5).abs() < 1e-12);
        }
        assert!(((a + b) * 0.5).norm() < 1e-15, "O_c at the middle of AB");
        assert!(c.x.abs() < 1e-15 && c.z.abs() < 1e-15 && c.y > 0.0);
        assert!(b.x > 0.0, "X_c points to B");
    }

    #[test]
    fn bad_arrays_are_typed_errors() {
        let p = Vector3::new(0.1f32, 0.2, 0.3);
        let z = Vector3::<f32>::zeros();
        let x = Vector3::x();
        assert_eq!(
            AntennaArray::new([p, p, z]),
            Err(ArrayError::CoincidentAntennas)
        );
        assert_eq!(
            AntennaArray::new([z, x, Vector3::new(f32::NAN, 0.0, 0.0)]),
            Err(ArrayError::NonFinite)
        );
        // collinear antennas are an array (paper 000 accepts them) that spans no plane
        let line = AntennaArray::new([z, x, x * 2.0]).unwrap();
        assert_eq!(line.check_spans_plane(), Err(ArrayError::CollinearAntennas));
        assert_eq!(
            AntennaArray::<f32>::paper_triangle(-1.0),
            Err(ArrayError::CoincidentAntennas)
        );
        assert_eq!(
            AntennaArray::<f32>::paper_triangle(f32::INFINITY),
            Err(ArrayError::NonFinite)
        );
    }
}
