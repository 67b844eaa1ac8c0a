//! The signal geometry of paper 003: the rotation `U(α)` of eq. (2), the phase offsets
//! `ψ_{P,i}(α)` of eqs. (4)/(24) of the antennas of an [`AntennaArray`] and their Jacobian
//! `∂Ψ/∂α` of eqs. (25)–(28).

use nalgebra::{Matrix3, Vector3};

use crate::attitude::array::AntennaArray;
use crate::geometry::Paper003Angles;
use crate::Real;

use super::trig::sin_cos;

/// `∂U/∂α`, `∂U/∂β`, `∂U/∂γ` of eq. (2) as printed, `U = R_z(γ) R_y(β) R_x'(α)` with the
/// passive `R_x'(α) = R_x(−α)`.
pub fn paper003_partials<T: Real>(angles: &Paper003Angles<T>) -> [Matrix3<T>; 3] {
    paper003_rotation_and_partials(angles).1
}

/// `U(α)` of eq. (2) and its three partial derivatives from one evaluation of the sines and
/// cosines (the fast single-precision ones of [`super::trig`]).
#[cfg_attr(feature = "optimize-cold", optimize(size))]
pub(crate) fn paper003_rotation_and_partials<T: Real>(
    angles: &Paper003Angles<T>,
) -> (Matrix3<T>, [Matrix3<T>; 3]) {
    let (sa, ca) = sin_cos(angles.alpha);
    let (sb, cb) = sin_cos(angles.beta);
    let (sg, cg) = sin_cos(angles.gamma);
    let (o, l) = (T::zero(), T::one());
    let rz = Matrix3::new(cg, -sg, o, sg, cg, o, o, o, l);
    let ry = Matrix3::new(cb, o, sb, o, l, o, -sb, o, cb);
    let rx = Matrix3::new(l, o, o, o, ca, sa, o, -sa, ca);
    // element-wise derivatives of the three factors
    let drz = Matrix3::new(-sg, -cg, o, cg, -sg, o, o, o, o);
    let dry = Matrix3::new(-sb, o, cb, o, o, o, -cb, o, -sb);
    let drx = Matrix3::new(o, o, o, o, -sa, ca, o, -ca, -sa);
    let ry_rx = ry * rx;
    (rz * ry_rx, [rz * ry * drx, rz * dry * rx, drz * ry_rx])
}

/// The phase model linearized at one attitude: the antennas' positions in the reference frame,
/// `v_P = U(α) r_P`, and their derivatives `∂v_P/∂α_j`, computed once per epoch and shared by
/// every satellite.
///
/// With `k = 2π/λ` and `μ_i` the unit line of sight to satellite `i` in the reference frame,
/// the phase of antenna `P` relative to `O_c` is `ψ_{P,i} = k μ_iᵀ U(α) r_P` (eqs. (4), (24)):
/// positive when the antenna is nearer the satellite than `O_c`, i.e. its carrier arrives
/// earlier and leads.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PhaseModel<T = f32> {
    wavenumber: T,
    positions: [Vector3<T>; 3],
    partials: [[Vector3<T>; 3]; 3],
}

impl<T: Real> PhaseModel<T> {
    /// The model at `angles` for carrier wavelength `wavelength_m` (metres; GPS L1
    /// 0.190 293 7 m).
    pub fn new(array: &AntennaArray<T>, wavelength_m: T, angles: &Paper003Angles<T>) -> Self {
        let (u, du) = paper003_rotation_and_partials(angles);
        let r = array.positions();
        Self {
            wavenumber: T::two_pi() / wavelength_m,
            positions: r.map(|p| u * p),
            partials: du.map(|d| r.map(|p| d * p)),
        }
    }

    /// The wavenumber `k = 2π/λ`, rad/m.
    pub fn wavenumber(&self) -> T {
        self.wavenumber
    }

    /// `ψ_{A,i}, ψ_{B,i}, ψ_{C,i}` of eq. (24) for the line of sight `los` (unit vector, reference
    /// frame, from the array to the satellite), radians.
    pub fn phases(&self, los: &Vector3<T>) -> Vector3<T> {
        let [a, b, c] = &self.positions;
        Vector3::new(los.dot(a), los.dot(b), los.dot(c)) * self.wavenumber
    }

    /// `∂ψ_{P,i}/∂α_j` of eqs. (26)–(28): row `P` (A, B, C), column `j` (α, β, γ), rad/rad.
    pub fn jacobian(&self, los: &Vector3<T>) -> Matrix3<T> {
        let k = self.wavenumber;
        let [da, db, dg] = &self.partials;
        let col = |d: &[Vector3<T>; 3]| {
            let [a, b, c] = d;
            Vector3::new(los.dot(a), los.dot(b), los.dot(c)) * k
        };
        Matrix3::from_columns(&[col(da), col(db), col(dg)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::is_rotation;

    fn los(az_deg: f64, el_deg: f64) -> Vector3<f64> {
        let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
        Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    }

    #[test]
    fn partials_match_finite_differences_of_eq_2() {
        let a = Paper003Angles::<f64>::new(0.3, -0.7, 1.9);
        let d = paper003_partials(&a);
        let h = 1e-6;
        let bump = |j: usize, s: f64| {
            let mut b = a;
            match j {
                0 => b.alpha += s,
                1 => b.beta += s,
                _ => b.gamma += s,
            }
            b.to_dcm()
        };
        for (j, dj) in d.iter().enumerate() {
            let fd = (bump(j, h) - bump(j, -h)) / (2.0 * h);
            assert!((fd - dj).norm() < 1e-9, "angle {j}: {}", (fd - dj).norm());
        }
        assert!(is_rotation(&a.to_dcm(), 1e-12));
        let (u, _) = paper003_rotation_and_partials(&a);
        assert!(
            (u - a.to_dcm()).norm() < 1e-15,
            "same U as geometry::Paper003Angles"
        );
        let a32 = Paper003Angles::<f32>::new(0.3, -0.7, 1.9);
        let (u32_, _) = paper003_rotation_and_partials(&a32);
        assert!((u32_ - a32.to_dcm()).norm() < 1e-6);
    }

    #[test]
    fn phases_and_jacobian_match_finite_differences() {
        let arr = AntennaArray::<f64>::paper_triangle(1.5).unwrap();
        let lambda = 0.190_293_7;
        let a = Paper003Angles::<f64>::new(-0.2, 0.4, 2.5);
        let mu = los(135.0, 30.0);
        let m = PhaseModel::new(&arr, lambda, &a);
        // ψ = k μᵀ U r_P written out
        let u = a.to_dcm();
        for (p, r) in arr.positions().iter().enumerate() {
            let psi = core::f64::consts::TAU / lambda * mu.dot(&(u * r));
            assert!((m.phases(&mu)[p] - psi).abs() < 1e-12);
        }
        let jac = m.jacobian(&mu);
        let h = 1e-6;
        for j in 0..3 {
            let mut up = a;
            let mut dn = a;
            match j {
                0 => (up.alpha, dn.alpha) = (a.alpha + h, a.alpha - h),
                1 => (up.beta, dn.beta) = (a.beta + h, a.beta - h),
                _ => (up.gamma, dn.gamma) = (a.gamma + h, a.gamma - h),
            }
            let fd = (PhaseModel::new(&arr, lambda, &up).phases(&mu)
                - PhaseModel::new(&arr, lambda, &dn).phases(&mu))
                / (2.0 * h);
            assert!((fd - jac.column(j)).norm() < 1e-7, "column {j}");
        }
    }

    #[test]
    fn rotation_about_y_c_moves_only_a_and_b_by_k_l_over_2_sin_el() {
        // spec (d): g_i = ∂ψ/∂β = k μ_z (l/2) (1, −1, 0) at β = 0 for the paper's triangle
        let arr = AntennaArray::<f64>::paper_triangle(1.5).unwrap();
        let lambda = 0.190_293_7;
        let k = core::f64::consts::TAU / lambda;
        let m = PhaseModel::new(&arr, lambda, &Paper003Angles::default());
        for el in [10.0, 45.0, 80.0] {
            let mu = los(45.0, el);
            let g = m.jacobian(&mu).column(1).into_owned();
            let expect = Vector3::new(1.0, -1.0, 0.0) * (k * 0.75 * mu.z);
            assert!(
                (g - expect).norm() < 1e-9 * k,
                "el {el}: {g:?} vs {expect:?}"
            );
        }
    }
}
