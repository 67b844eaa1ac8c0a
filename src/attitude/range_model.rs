//! Paper 002's measurement model and the validated inputs of the snapshot solvers: range
//! differences (ambiguities known) and raw single-difference phase and code (for
//! [`super::ambiguity`]).
//!
//! Eq. (1)–(2): `Δr_ij = b_iᵀ A s_j`, or `R = Bᵀ A S` for `m` baselines (rows) and `n`
//! satellites (columns), with `A = C_br` (reference to body), `b_i` the body baselines and
//! `s_j` the unit lines of sight in the reference frame (seed specification, Paper 002 (a)).
//!
//! Noise model of every solver in this module tree: the range differences of satellite `j`
//! (one per baseline) have covariance `σ_j² Σ_B`, independent between satellites. `Σ_B` is the
//! `m × m` baseline correlation: the identity for independent single differences, or
//! `(I + 11ᵀ)/2` when each single difference is the difference of two equally noisy antenna
//! phases and all share the base antenna (then `σ_j` is the standard deviation of one single
//! difference).

use heapless::Vec;
use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::attitude::snapshot::SnapshotError;
use crate::{real, Real};

/// The largest number of satellites the crate's examples and budgets use (the paper's "up to
/// 12"); the observation types take their capacity as a const generic `N`.
pub const MAX_SATELLITES: usize = 12;

/// The range differences of one satellite on every baseline.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SatelliteRanges<const M: usize, T = f32> {
    /// Satellite id (PRN); ids must be unique within an epoch.
    pub id: u8,
    /// Unit line of sight from the array to the satellite, reference frame.
    pub los: Vector3<T>,
    /// `Δr_ij = ρ_0j − ρ_ij` for baselines `i = 1..m`, metres (carrier phase with known
    /// integer ambiguities, times the wavelength).
    pub range_diff: [T; M],
    /// Standard deviation of one range difference, metres (`> 0`).
    pub sigma: T,
}

/// One epoch of range differences for up to `N` satellites, validated on insertion.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RangeDifferences<const M: usize, const N: usize, T = f32> {
    sats: Vec<SatelliteRanges<M, T>, N>,
}

impl<const M: usize, const N: usize, T: Real> RangeDifferences<M, N, T> {
    /// An empty epoch.
    pub fn new() -> Self {
        Self { sats: Vec::new() }
    }

    /// Adds a satellite.
    ///
    /// # Errors
    /// [`SnapshotError::NonFinite`], [`SnapshotError::InvalidLineOfSight`] (norm off 1 by more
    /// than 1e-3), [`SnapshotError::InvalidNoise`] (`σ ≤ 0`),
    /// [`SnapshotError::DuplicateSatellite`], [`SnapshotError::TooManySatellites`]. The set is
    /// unchanged on error.
    pub fn push(&mut self, sat: SatelliteRanges<M, T>) -> Result<(), SnapshotError> {
        if !(sat.range_diff.iter().all(|v| v.is_finite()) && sat.sigma.is_finite()) {
            return Err(SnapshotError::NonFinite);
        }
        check_los(&sat.los)?;
        if !(sat.sigma > T::zero()) {
            return Err(SnapshotError::InvalidNoise);
        }
        push_unique(&mut self.sats, sat, |s| s.id)
    }

    /// The satellites, in insertion order.
    pub fn satellites(&self) -> &[SatelliteRanges<M, T>] {
        &self.sats
    }

    /// Number of satellites.
    pub fn len(&self) -> usize {
        self.sats.len()
    }

    /// True when no satellite has been added.
    pub fn is_empty(&self) -> bool {
        self.sats.is_empty()
    }

    /// Removes every satellite.
    pub fn clear(&mut self) {
        self.sats.clear();
    }
}

/// Raw single differences of one satellite on every baseline.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PhaseSatellite<const M: usize, T = f32> {
    /// Satellite id (PRN); unique within an epoch.
    pub id: u8,
    /// Unit line of sight to the satellite, reference frame.
    pub los: Vector3<T>,
    /// SD carrier phase `Φ_0 − Φ_i` per baseline, cycles (phase counted as a range: it grows
    /// with distance), calibrated line biases removed, any integer offset allowed. Keep
    /// `|φ| ≲ 10⁴` cycles in `f32` (remove whole cycles first).
    pub phase_cycles: [T; M],
    /// SD code `ρ_0 − ρ_i` per baseline, metres.
    pub code_m: [T; M],
    /// Variance multiplier of this satellite (1 nominal, e.g. `1/sin²(elevation)`), `> 0`.
    pub cofactor: T,
}

/// One epoch of raw single differences for up to `N` satellites, validated on insertion.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PhaseObservations<const M: usize, const N: usize, T = f32> {
    sats: Vec<PhaseSatellite<M, T>, N>,
}

impl<const M: usize, const N: usize, T: Real> PhaseObservations<M, N, T> {
    /// An empty epoch.
    pub fn new() -> Self {
        Self { sats: Vec::new() }
    }

    /// Adds a satellite.
    ///
    /// # Errors
    /// [`SnapshotError::NonFinite`], [`SnapshotError::InvalidLineOfSight`],
    /// [`SnapshotError::InvalidNoise`] (cofactor `≤ 0`), [`SnapshotError::DuplicateSatellite`],
    /// [`SnapshotError::TooManySatellites`]. Unchanged on error.
    pub fn push(&mut self, sat: PhaseSatellite<M, T>) -> Result<(), SnapshotError> {
        let finite = sat.phase_cycles.iter().all(|v| v.is_finite())
            && sat.code_m.iter().all(|v| v.is_finite())
            && sat.cofactor.is_finite();
        if !finite {
            return Err(SnapshotError::NonFinite);
        }
        check_los(&sat.los)?;
        if !(sat.cofactor > T::zero()) {
            return Err(SnapshotError::InvalidNoise);
        }
        push_unique(&mut self.sats, sat, |s| s.id)
    }

    /// The satellites, in insertion order.
    pub fn satellites(&self) -> &[PhaseSatellite<M, T>] {
        &self.sats
    }

    /// Number of satellites.
    pub fn len(&self) -> usize {
        self.sats.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.sats.is_empty()
    }
}

/// Appends `sat` unless a satellite with its identifier is already there.
fn push_unique<S, const N: usize>(
    sats: &mut Vec<S, N>,
    sat: S,
    id: impl Fn(&S) -> u8,
) -> Result<(), SnapshotError> {
    if sats.iter().any(|s| id(s) == id(&sat)) {
        return Err(SnapshotError::DuplicateSatellite);
    }
    // (the refused satellite is dropped: the caller learns the set is full)
    sats.push(sat).map_err(|_| SnapshotError::TooManySatellites)
}

/// Checks that a line of sight is finite and of unit length (to 1e-3).
pub(crate) fn check_los<T: Real>(los: &Vector3<T>) -> Result<(), SnapshotError> {
    if !los.iter().all(|v| v.is_finite()) {
        return Err(SnapshotError::NonFinite);
    }
    if !((los.norm() - T::one()).abs() <= real(1e-3)) {
        return Err(SnapshotError::InvalidLineOfSight);
    }
    Ok(())
}

/// The weighted line-of-sight normal matrix `N = Σ_j w_j s_j s_jᵀ` (`S W Sᵀ`) and its
/// Cholesky inverse, after the coplanarity test.
///
/// # Errors
/// [`SnapshotError::TooFewSatellites`] for `n < 3`; [`SnapshotError::CoplanarLineOfSight`] when
/// `det N / (tr N / 3)³ < 1e-5` (the lines of sight span less than three dimensions) or `N` is
/// not positive definite.
pub(crate) fn los_normal_matrix<T: Real>(
    los_weights: impl Iterator<Item = (Vector3<T>, T)> + Clone,
) -> Result<(Matrix3<T>, Matrix3<T>), SnapshotError> {
    let mut n = Matrix3::<T>::zeros();
    let mut count = 0usize;
    for (s, w) in los_weights {
        n += s * s.transpose() * w;
        count = count.saturating_add(1);
    }
    if count < 3 {
        return Err(SnapshotError::TooFewSatellites);
    }
    let mean = n.trace() / real(3.0);
    if !(mean > T::zero()) || !mean.is_finite() {
        return Err(SnapshotError::Numerical);
    }
    let shape = n.determinant() / (mean * mean * mean);
    if !(shape >= real(1e-5)) {
        return Err(SnapshotError::CoplanarLineOfSight);
    }
    let inverse = n
        .cholesky()
        .map(|c| c.inverse())
        .ok_or(SnapshotError::CoplanarLineOfSight)?;
    Ok((n, inverse))
}

/// The body baselines `b_1..b_m` of an antenna array, validated.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Baselines<const M: usize, T = f32> {
    b: [Vector3<T>; M],
}

impl<const M: usize, T: Real> Baselines<M, T> {
    /// Validates the baselines (base antenna to antenna `i`, body axes, metres).
    ///
    /// # Errors
    /// [`SnapshotError::TooFewBaselines`] for `M < 2`; [`SnapshotError::NonFinite`];
    /// [`SnapshotError::ZeroBaseline`] for a baseline shorter than 1 mm;
    /// [`SnapshotError::CollinearBaselines`] when `|b_1 × b_2| < 1e-3 |b_1| |b_2|` (the first two
    /// baselines must span a plane; they give the appended cross-product baseline).
    pub fn new(b: [Vector3<T>; M]) -> Result<Self, SnapshotError> {
        if M < 2 {
            return Err(SnapshotError::TooFewBaselines);
        }
        if !b.iter().all(|v| v.iter().all(|x| x.is_finite())) {
            return Err(SnapshotError::NonFinite);
        }
        if b.iter().any(|v| !(v.norm() >= real(1e-3))) {
            return Err(SnapshotError::ZeroBaseline);
        }
        let (Some(b1), Some(b2)) = (b.first(), b.get(1)) else {
            return Err(SnapshotError::TooFewBaselines);
        };
        if !(b1.cross(b2).norm() >= b1.norm() * b2.norm() * real(1e-3)) {
            return Err(SnapshotError::CollinearBaselines);
        }
        Ok(Self { b })
    }

    /// The baselines, body axes, metres.
    pub fn as_array(&self) -> &[Vector3<T>; M] {
        &self.b
    }

    /// `G = B Bᵀ = Σ b_i b_iᵀ` (paper eq. (3)), m².
    pub fn gram(&self) -> Matrix3<T> {
        self.b
            .iter()
            .fold(Matrix3::zeros(), |g, b| g + b * b.transpose())
    }

    /// Model eq. (1): the range differences `Δr_ij = b_iᵀ A s_j = b_i · (C_rbᵀ s_j)` of one
    /// satellite, metres.
    pub fn range_differences(&self, c_rb: &Matrix3<T>, los: &Vector3<T>) -> [T; M] {
        let s_body = c_rb.transpose() * los;
        let mut r = [T::zero(); M];
        for (ri, bi) in r.iter_mut().zip(self.b.iter()) {
            *ri = bi.dot(&s_body);
        }
        r
    }
}

/// A baseline correlation matrix `Σ_B` (symmetric positive definite) and its inverse.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BaselineCorrelation<const M: usize, T = f32> {
    sigma: SMatrix<T, M, M>,
    inverse: SMatrix<T, M, M>,
}

impl<const M: usize, T: Real> BaselineCorrelation<M, T> {
    /// Validates `Σ_B`.
    ///
    /// # Errors
    /// [`SnapshotError::NonFinite`]; [`SnapshotError::InvalidCorrelation`] if it is not
    /// symmetric (to 1e-6 relative) positive definite.
    pub fn new(sigma: SMatrix<T, M, M>) -> Result<Self, SnapshotError> {
        if !sigma.iter().all(|v| v.is_finite()) {
            return Err(SnapshotError::NonFinite);
        }
        let asym = (sigma - sigma.transpose()).norm();
        if !(asym <= sigma.norm() * real(1e-6)) {
            return Err(SnapshotError::InvalidCorrelation);
        }
        let inverse = sigma
            .cholesky()
            .map(|c| c.inverse())
            .ok_or(SnapshotError::InvalidCorrelation)?;
        if !inverse.iter().all(|v| v.is_finite()) {
            return Err(SnapshotError::InvalidCorrelation);
        }
        Ok(Self { sigma, inverse })
    }

    /// Independent single differences: `Σ_B = I`.
    pub fn independent() -> Self {
        Self {
            sigma: SMatrix::identity(),
            inverse: SMatrix::identity(),
        }
    }

    /// Single differences that share the base antenna, with equal antenna noise:
    /// `Σ_B = (I + 11ᵀ)/2` (unit diagonal, correlation 0.5).
    pub fn shared_base_antenna() -> Self {
        let half: T = real(0.5);
        let sigma = SMatrix::<T, M, M>::from_fn(|i, j| if i == j { T::one() } else { half });
        // (I + 11ᵀ)/2 is positive definite for every M ≥ 1; fall back to I if rounding says
        // otherwise (it cannot for M ≤ 12).
        Self::new(sigma).unwrap_or_else(|_| Self::independent())
    }

    /// `Σ_B`.
    pub fn matrix(&self) -> &SMatrix<T, M, M> {
        &self.sigma
    }

    /// `Σ_B⁻¹`.
    pub fn inverse(&self) -> &SMatrix<T, M, M> {
        &self.inverse
    }
}
