//! Geometry, noise and bounds shared by the `snapshot` variants (f64, host-sim's own code).

use gnss_attitude::attitude::range_model::{RangeDifferences, SatelliteRanges};
use gnss_attitude::geometry::Euler321;
use nalgebra::{Matrix3, SMatrix, Vector3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The paper's three-antenna array: `b1 = (1, 0, 0)`, `b2 = (0.5, √3/2, 0)` m (body).
pub fn triangle() -> [Vector3<f64>; 2] {
    [
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.5, 0.75f64.sqrt(), 0.0),
    ]
}

/// A regular tetrahedron of 1 m edges: the triangle plus `(0.5, √3/6, √(2/3))` m.
pub fn tetrahedron() -> [Vector3<f64>; 3] {
    let [b1, b2] = triangle();
    [
        b1,
        b2,
        Vector3::new(0.5, 3f64.sqrt() / 6.0, (2.0f64 / 3.0).sqrt()),
    ]
}

/// Unit line of sight in a local-level frame with z to nadir (NED-like) from elevation and
/// azimuth in degrees.
pub fn los_deg(elevation: f64, azimuth: f64) -> Vector3<f64> {
    let (se, ce) = elevation.to_radians().sin_cos();
    let (sa, ca) = azimuth.to_radians().sin_cos();
    Vector3::new(ce * ca, ce * sa, -se)
}

/// The paper's recommended sky: elevations 60/45/30°, azimuths 0/120/240°.
pub fn paper_sky() -> [Vector3<f64>; 3] {
    [
        los_deg(60.0, 0.0),
        los_deg(45.0, 120.0),
        los_deg(30.0, 240.0),
    ]
}

/// A standard normal sample.
pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    <StandardNormal as Distribution<f64>>::sample(&StandardNormal, rng)
}

/// A rotation drawn uniformly from SO(3) (normalized Gaussian quaternion), as `C_rb`.
pub fn random_rotation(rng: &mut ChaCha8Rng) -> Matrix3<f64> {
    let q = nalgebra::Quaternion::new(normal(rng), normal(rng), normal(rng), normal(rng));
    nalgebra::UnitQuaternion::from_quaternion(q)
        .to_rotation_matrix()
        .into_inner()
}

/// Range differences `Δr_ij = b_i · (C_rbᵀ s_j)` plus noise with covariance `σ² Σ_B`
/// (`chol_b` = Cholesky factor of `Σ_B`), as the core's f32 input.
pub fn noisy_ranges<const M: usize>(
    baselines: &[Vector3<f64>; M],
    c_rb: &Matrix3<f64>,
    sky: &[Vector3<f64>],
    sigma: f64,
    chol_b: &SMatrix<f64, M, M>,
    rng: &mut ChaCha8Rng,
) -> anyhow::Result<RangeDifferences<M, 12, f32>> {
    let mut obs = RangeDifferences::new();
    for (j, s) in sky.iter().enumerate() {
        let s_body = c_rb.transpose() * s;
        let white = nalgebra::SVector::<f64, M>::from_fn(|_, _| normal(rng));
        let noise = chol_b * white * sigma;
        let range_diff: [f32; M] =
            std::array::from_fn(|i| (baselines[i].dot(&s_body) + noise[i]) as f32);
        obs.push(SatelliteRanges {
            id: j as u8 + 1,
            los: s.cast::<f32>(),
            range_diff,
            sigma: sigma as f32,
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    Ok(obs)
}

/// Cramér–Rao bound of the body-frame rotation-vector error for range differences with
/// covariance `σ² Σ_B` per satellite: `J = Σ_j Σ_ik (Σ_B⁻¹)_ik h_ij h_kjᵀ / σ²`,
/// `h_ij = b_i × (C_rbᵀ s_j)`; returns `J⁻¹`, rad².
pub fn crb_body<const M: usize>(
    baselines: &[Vector3<f64>; M],
    c_rb: &Matrix3<f64>,
    sky: &[Vector3<f64>],
    sigma: f64,
    sigma_b: &SMatrix<f64, M, M>,
) -> Option<Matrix3<f64>> {
    let w = sigma_b.try_inverse()?;
    let mut j = Matrix3::zeros();
    for s in sky {
        let u = c_rb.transpose() * s;
        for i in 0..M {
            for k in 0..M {
                j += baselines[i].cross(&u) * baselines[k].cross(&u).transpose() * w[(i, k)];
            }
        }
    }
    (j / (sigma * sigma)).try_inverse()
}

/// Standard deviations `[heading, roll, pitch]` (degrees) of 3-2-1 angles at `truth` from a
/// body-frame rotation-vector covariance (`δ_body = E (δroll, δpitch, δyaw)`).
pub fn euler_sigma_deg(cov_body: &Matrix3<f64>, truth: &Euler321<f64>) -> [f64; 3] {
    let (sr, cr) = truth.roll.sin_cos();
    let (sp, cp) = truth.pitch.sin_cos();
    let e = Matrix3::new(1.0, 0.0, -sp, 0.0, cr, sr * cp, 0.0, -sr, cr * cp);
    let e_inv = e.try_inverse().unwrap_or_else(Matrix3::identity);
    let p = e_inv * cov_body * e_inv.transpose();
    [
        p[(2, 2)].sqrt().to_degrees(),
        p[(0, 0)].sqrt().to_degrees(),
        p[(1, 1)].sqrt().to_degrees(),
    ]
}

/// `[heading, roll, pitch]` errors in degrees, each wrapped into (−180°, 180°].
pub fn euler_errors_deg(estimate: &Matrix3<f64>, truth: &Euler321<f64>) -> [f64; 3] {
    let e = Euler321::from_dcm(estimate).unwrap_or(Euler321::new(f64::NAN, f64::NAN, f64::NAN));
    let wrap = |a: f64| {
        let w = (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        w.to_degrees()
    };
    [
        wrap(e.yaw - truth.yaw),
        wrap(e.roll - truth.roll),
        wrap(e.pitch - truth.pitch),
    ]
}

/// Per-axis column of a list of `[heading, roll, pitch]` triples.
pub fn column(values: &[[f64; 3]], axis: usize) -> Vec<f64> {
    values.iter().map(|v| v[axis]).collect()
}

/// Seeded generator for Monte Carlo epoch `k` of a run.
pub fn epoch_rng(seed: u64, salt: u64, k: usize) -> ChaCha8Rng {
    use rand::SeedableRng;
    ChaCha8Rng::seed_from_u64(
        seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(salt.wrapping_mul(1_000_003))
            .wrapping_add(k as u64),
    )
}

/// A uniform integer in `lo..=hi`.
pub fn uniform_int(rng: &mut ChaCha8Rng, lo: i64, hi: i64) -> i64 {
    rng.random_range(lo..=hi)
}
