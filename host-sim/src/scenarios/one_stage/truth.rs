//! Truth of the one-stage scenario, in f64 and independent of the core: the sky (geometry G1
//! of the spec), the antenna triangle, the attitude history and the antennas' phases.

use nalgebra::{Matrix3, Vector3};

/// GPS L1 wavelength used throughout, m (`c / 1575.42 MHz`). The paper's GLONASS L1
/// (0.1871 m) would make every figure 1.7 % smaller.
pub const WAVELENGTH_M: f64 = 299_792_458.0 / 1_575.42e6;
/// Side of the antenna triangle, m.
pub const SIDE_M: f64 = 1.5;

/// One satellite of the sky: PRN and unit line of sight in the reference frame `OXYZ`
/// (`Z` up; azimuth from `X` towards `Y`).
#[derive(Clone, Copy, Debug)]
pub struct Satellite {
    /// PRN.
    pub prn: u8,
    /// Azimuth, degrees (from X towards Y).
    pub azimuth_deg: f64,
    /// Elevation, degrees.
    pub elevation_deg: f64,
}

impl Satellite {
    /// Unit line of sight, reference frame.
    pub fn los(&self) -> Vector3<f64> {
        let (az, el) = (
            self.azimuth_deg.to_radians(),
            self.elevation_deg.to_radians(),
        );
        Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    }
}

/// Geometry G1 of the spec: satellite `i = 1..8` at azimuth `45°(i−1)`, elevation `10°·i`;
/// the first `n` of them ("first 2" = elevations 10° and 20°).
pub fn sky_g1(n: usize) -> Vec<Satellite> {
    (1..=n.min(8))
        .map(|i| Satellite {
            prn: i as u8,
            azimuth_deg: 45.0 * (i as f64 - 1.0),
            elevation_deg: 10.0 * i as f64,
        })
        .collect()
}

/// The paper's equilateral triangle in body axes: `O_c` at the middle of AB, `X_c` to B,
/// `Y_c` to C. Metres.
pub fn antennas() -> [Vector3<f64>; 3] {
    let h = SIDE_M / 2.0;
    [
        Vector3::new(-h, 0.0, 0.0),
        Vector3::new(h, 0.0, 0.0),
        Vector3::new(0.0, SIDE_M * 3f64.sqrt() / 2.0, 0.0),
    ]
}

/// The body-to-reference rotation for a rotation by `beta` about `Y_c` (α = γ = 0 in eq. (2)):
/// turns `Z` towards `X`.
pub fn rotation_about_y(beta: f64) -> Matrix3<f64> {
    let (s, c) = beta.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// `U(α, β, γ)` of paper 003 eq. (2) as printed (host's own implementation):
/// `R_z(γ) · R_y(β) · R_x'(α)` with `R_x'(α)` rows `(1 0 0), (0 cos α sin α), (0 −sin α cos α)`.
pub fn paper003_u(alpha: f64, beta: f64, gamma: f64) -> Matrix3<f64> {
    let (sa, ca) = alpha.sin_cos();
    let (sg, cg) = gamma.sin_cos();
    let rz = Matrix3::new(cg, -sg, 0.0, sg, cg, 0.0, 0.0, 0.0, 1.0);
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, ca, sa, 0.0, -sa, ca);
    rz * rotation_about_y(beta) * rx
}

/// Phases `ψ_P = 2π/λ μᵀ C_rb r_P` of the three antennas for one line of sight, rad.
pub fn phases(c_rb: &Matrix3<f64>, los: &Vector3<f64>) -> [f64; 3] {
    let k = std::f64::consts::TAU / WAVELENGTH_M;
    antennas().map(|r| k * los.dot(&(c_rb * r)))
}

/// Angular motion about `Y_c`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// `β = 0` throughout (the spec's recommended reading of the paper).
    Static,
    /// The spec's motion A: `β̇ = (a0/V0) sin νt`, `V0 = 300 m/s`, `a0 = 40 m/s²`,
    /// `ν = 2π/300 s⁻¹` (peak rate 0.133 rad/s, peak acceleration 2.8e-3 rad/s²).
    MotionA,
}

/// Motion A's constants.
const V0: f64 = 300.0;
const A0: f64 = 40.0;
const NU: f64 = std::f64::consts::TAU / 300.0;

impl Motion {
    /// `β(t)`, rad.
    pub fn beta(&self, t: f64) -> f64 {
        match self {
            Self::Static => 0.0,
            // β = (a0/(V0 ν)) (1 − cos νt), so β̇ = (a0/V0) sin νt
            Self::MotionA => A0 / (V0 * NU) * (1.0 - (NU * t).cos()),
        }
    }
}
