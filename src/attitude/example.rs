//! A deterministic example epoch for documentation, benchmarks, the firmware budgets and
//! self-checks: the paper's 1 m triangle at a fixed attitude on a fixed 8-satellite sky, with
//! seeded noise ([`crate::noise`]), as ranges (ambiguities known) or as raw single differences.
//!
//! ```
//! use gnss_attitude::attitude::example;
//! let resolver = example::resolver()?;
//! let fix = resolver.resolve(&example::phases(8, 1)?)?;
//! assert_eq!(fix.ambiguities[0][0], example::ambiguity(0, 0));
//! let truth = example::attitude().to_quaternion();
//! assert!(fix.solution.q_rb.angle_to(&truth) < 0.02);
//! # Ok::<(), gnss_attitude::attitude::ambiguity::AmbiguityError>(())
//! ```

use nalgebra::Vector3;

use crate::attitude::snapshot::SnapshotError;
use crate::geometry::Euler321;
use crate::noise::{SplitMix64, StandardNormal};

use super::ambiguity::{
    AmbiguityConfig, AmbiguityResolver, PhaseObservations, PhaseSatellite, GPS_L1_WAVELENGTH_M,
};
use super::range_model::{BaselineCorrelation, Baselines, RangeDifferences, SatelliteRanges};
use super::snapshot::SnapshotSolver;

/// The sky: (PRN, elevation °, azimuth °) in a local-level frame with z to nadir.
pub const SKY: [(u8, f32, f32); 8] = [
    (3, 72.0, 15.0),
    (7, 55.0, 110.0),
    (11, 48.0, 230.0),
    (14, 38.0, 300.0),
    (19, 30.0, 40.0),
    (22, 24.0, 170.0),
    (27, 18.0, 260.0),
    (31, 12.0, 340.0),
];

/// Single-difference phase noise, metres (per-antenna 3 mm/√2).
pub const PHASE_SIGMA_M: f32 = 0.003;
/// Single-difference code noise, metres.
pub const CODE_SIGMA_M: f32 = 0.3;

/// The true attitude: heading 2 rad, pitch 0.3 rad, roll −0.5 rad.
pub fn attitude() -> Euler321<f32> {
    Euler321::new(2.0, 0.3, -0.5)
}

/// The true integer ambiguity of baseline `i`, satellite `j` (cycles).
pub fn ambiguity(i: usize, j: usize) -> i32 {
    (j as i32 * 7 + i as i32 * 13) % 23 - 11
}

/// The paper's triangle, `b1 = (1, 0, 0)`, `b2 = (0.5, √3/2, 0)` m.
///
/// # Errors
/// None in practice (the baselines are valid); the type keeps the crate's no-panic rule.
pub fn baselines() -> Result<Baselines<2, f32>, SnapshotError> {
    Baselines::new([
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.5, 0.866_025_4, 0.0),
    ])
}

/// The snapshot solver for the triangle, single differences sharing antenna 0.
///
/// # Errors
/// As [`baselines`].
pub fn solver() -> Result<SnapshotSolver<2, f32>, SnapshotError> {
    Ok(SnapshotSolver::new(
        baselines()?,
        BaselineCorrelation::shared_base_antenna(),
    ))
}

/// The constrained ambiguity resolver for the triangle (GPS L1, 3 mm / 0.3 m).
///
/// # Errors
/// As [`baselines`].
pub fn resolver() -> Result<AmbiguityResolver<2, f32>, SnapshotError> {
    AmbiguityResolver::new(
        solver()?,
        AmbiguityConfig::gps_l1(PHASE_SIGMA_M, CODE_SIGMA_M),
    )
}

fn los(elevation_deg: f32, azimuth_deg: f32) -> Vector3<f32> {
    let (se, ce) = libm::sincosf(elevation_deg.to_radians());
    let (sa, ca) = libm::sincosf(azimuth_deg.to_radians());
    Vector3::new(ce * ca, ce * sa, -se)
}

/// Per-antenna noise for 3 antennas → the two single differences (antenna 0 shared).
fn sd_noise(normal: &mut StandardNormal, rng: &mut SplitMix64, sd_sigma: f32) -> [f32; 2] {
    let s = sd_sigma * core::f32::consts::FRAC_1_SQRT_2;
    let e0 = normal.sample(rng) * s;
    let e1 = normal.sample(rng) * s;
    let e2 = normal.sample(rng) * s;
    [e0 - e1, e0 - e2]
}

/// Raw single differences of the first `n` satellites of [`SKY`] (at most 8), seeded noise.
///
/// # Errors
/// [`SnapshotError`] from the observation set (none for `n ≤ 8`).
pub fn phases(n: usize, seed: u64) -> Result<PhaseObservations<2, 12, f32>, SnapshotError> {
    let c_rb = attitude().to_dcm();
    let b = baselines()?;
    let mut rng = SplitMix64::new(seed);
    let mut normal = StandardNormal::new();
    let lambda = GPS_L1_WAVELENGTH_M as f32;
    let mut obs = PhaseObservations::new();
    for (j, &(prn, el, az)) in SKY.iter().enumerate().take(n) {
        let s = los(el, az);
        let geometric = b.range_differences(&c_rb, &s);
        let ph = sd_noise(&mut normal, &mut rng, PHASE_SIGMA_M);
        let co = sd_noise(&mut normal, &mut rng, CODE_SIGMA_M);
        obs.push(PhaseSatellite {
            id: prn,
            los: s,
            phase_cycles: core::array::from_fn(|i| {
                (geometric[i] + ph[i]) / lambda + ambiguity(i, j) as f32
            }),
            code_m: core::array::from_fn(|i| geometric[i] + co[i]),
            cofactor: 1.0,
        })?;
    }
    Ok(obs)
}

/// Range differences (ambiguities known) of the first `n` satellites of [`SKY`], 4 mm noise.
///
/// # Errors
/// [`SnapshotError`] from the observation set (none for `n ≤ 8`).
pub fn ranges(n: usize, seed: u64) -> Result<RangeDifferences<2, 12, f32>, SnapshotError> {
    let c_rb = attitude().to_dcm();
    let b = baselines()?;
    let mut rng = SplitMix64::new(seed);
    let mut normal = StandardNormal::new();
    let mut obs = RangeDifferences::new();
    for &(prn, el, az) in SKY.iter().take(n) {
        let s = los(el, az);
        let geometric = b.range_differences(&c_rb, &s);
        let noise = [normal.sample(&mut rng), normal.sample(&mut rng)];
        obs.push(SatelliteRanges {
            id: prn,
            los: s,
            range_diff: core::array::from_fn(|i| geometric[i] + 0.004 * noise[i]),
            sigma: 0.004,
        })?;
    }
    Ok(obs)
}
