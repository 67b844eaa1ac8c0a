//! Property tests of the snapshot solvers: for random rotations and random geometries the
//! solver never returns a reflection or a NaN, and no input (NaN, infinities, garbage phases)
//! makes any entry point panic.

use gnss_attitude::attitude::ambiguity::{
    AmbiguityConfig, AmbiguityResolver, PhaseObservations, PhaseSatellite,
};
use gnss_attitude::attitude::paper002::paper_formula;
use gnss_attitude::attitude::range_model::{
    BaselineCorrelation, Baselines, RangeDifferences, SatelliteRanges,
};
use gnss_attitude::attitude::snapshot::SnapshotSolver;
use gnss_attitude::attitude::wahba::{solve_wahba, WahbaPair};
use gnss_attitude::geometry::{rot_x, rot_y, rot_z, rotation_angle};
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;

fn unit(az: f64, el: f64) -> Vector3<f64> {
    Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), -el.sin())
}

fn rotation(a: [f64; 3]) -> Matrix3<f64> {
    rot_z(a[0]) * rot_y(a[1]) * rot_x(a[2])
}

fn is_proper_finite(c: &Matrix3<f32>) -> bool {
    c.iter().all(|v| v.is_finite())
        && c.determinant() > 0.0
        && (c.transpose() * c - Matrix3::identity()).norm() < 1e-4
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    /// Random attitude, random sky of 3–12 satellites, random non-collinear baselines, noise
    /// from none to decimetres: a solution is a proper rotation with finite covariance, and
    /// with small noise it is close to the truth.
    #[test]
    fn random_geometries_never_give_a_reflection_or_nan(
        angles in prop::array::uniform3(-3.2f64..3.2),
        sky in prop::collection::vec((0.0f64..6.3, 0.05f64..1.5), 3..=12),
        b1 in prop::array::uniform3(-2.0f64..2.0),
        b2 in prop::array::uniform3(-2.0f64..2.0),
        noise_exp in -6.0f64..-0.5,
        seed in any::<u64>(),
    ) {
        let c_rb = rotation(angles);
        let b = [Vector3::from(b1), Vector3::from(b2)];
        let Ok(baselines) = Baselines::new(b.map(|v| v.cast::<f32>())) else { return Ok(()); };
        let solver = SnapshotSolver::new(baselines, BaselineCorrelation::shared_base_antenna());
        let sigma = 10f64.powf(noise_exp);
        let mut state = seed | 1;
        let mut noise = || {
            // xorshift, mapped to ±√3 σ uniform (variance σ²)
            state ^= state << 13; state ^= state >> 7; state ^= state << 17;
            ((state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * sigma * 3f64.sqrt()
        };
        let mut obs = RangeDifferences::<2, 12, f32>::new();
        for (j, &(az, el)) in sky.iter().enumerate() {
            let s = unit(az, el);
            let u = c_rb.transpose() * s;
            let r: [f32; 2] = std::array::from_fn(|i| (b[i].dot(&u) + noise()) as f32);
            obs.push(SatelliteRanges { id: j as u8, los: s.cast(), range_diff: r, sigma: sigma as f32 }).unwrap();
        }
        if let Ok(sol) = solver.solve(&obs) {
            prop_assert!(is_proper_finite(&sol.c_rb));
            prop_assert!(sol.covariance.iter().all(|v| v.is_finite()));
            prop_assert!(sol.residual_rms.is_finite() && sol.chi_square.is_finite());
            let q = sol.q_rb;
            prop_assert!((q.norm() - 1.0).abs() < 1e-5);
            let spread = b[0].norm().min(b[1].norm());
            if sigma < 1e-4 && spread > 0.2 && b[0].cross(&b[1]).norm() > 0.1 * b[0].norm() * b[1].norm() {
                let err = rotation_angle(&(c_rb.transpose() * sol.c_rb.cast::<f64>()));
                let bound = 50.0 * sol.covariance.trace().sqrt() as f64 + 1e-4;
                prop_assert!(err < bound, "error {} bound {}", err, bound);
            }
        }
    }

    /// Wahba's solver on random pairs and weights spanning twelve orders of magnitude returns
    /// a unit quaternion (hence a proper rotation) or a typed error.
    #[test]
    fn wahba_never_reflects(
        pairs in prop::collection::vec((prop::array::uniform3(-10f32..10.0), prop::array::uniform3(-10f32..10.0), -6f32..6.0), 1..6),
    ) {
        let p: Vec<WahbaPair<f32>> = pairs.iter().map(|(b, r, w)| WahbaPair {
            body: Vector3::from(*b), reference: Vector3::from(*r), weight: 10f32.powf(*w),
        }).collect();
        if let Ok(sol) = solve_wahba(&p) {
            prop_assert!((sol.q_rb.norm() - 1.0).abs() < 1e-5);
            prop_assert!(is_proper_finite(&sol.q_rb.to_dcm()));
        }
    }

    /// Garbage in (NaN, infinities, huge values, duplicate ids, non-unit lines of sight) never
    /// panics any entry point; what is accepted yields finite output or a typed error.
    #[test]
    fn no_input_panics_the_snapshot_entry_points(
        sats in prop::collection::vec((any::<u8>(), prop::array::uniform3(prop_oneof![any::<f32>(), -1f32..1.0]),
            prop::array::uniform3(prop_oneof![any::<f32>(), -1e3f32..1e3]), prop::array::uniform3(prop_oneof![any::<f32>(), -10f32..10.0]),
            prop_oneof![any::<f32>(), 1e-4f32..10.0]), 0..14),
        b in prop::array::uniform9(prop_oneof![any::<f32>(), -2f32..2.0]),
    ) {
        let bl = [Vector3::new(b[0], b[1], b[2]), Vector3::new(b[3], b[4], b[5]), Vector3::new(b[6], b[7], b[8])];
        let three = Baselines::new(bl);
        let two = Baselines::new([bl[0], bl[1]]);
        let mut ranges3 = RangeDifferences::<3, 12, f32>::new();
        let mut ranges2 = RangeDifferences::<2, 12, f32>::new();
        let mut phases = PhaseObservations::<2, 12, f32>::new();
        for (id, los, ph, code, s) in &sats {
            let mut l = Vector3::from(*los);
            if l.iter().all(|v| v.is_finite()) && l.norm() > 1e-3 && l.norm() < 1e3 { l = l.normalize(); }
            let _ = ranges3.push(SatelliteRanges { id: *id, los: l, range_diff: *ph, sigma: *s });
            let _ = ranges2.push(SatelliteRanges { id: *id, los: l, range_diff: [ph[0], ph[1]], sigma: *s });
            let _ = phases.push(PhaseSatellite { id: *id, los: l, phase_cycles: [ph[0], ph[1]], code_m: [code[0], code[1]], cofactor: *s });
        }
        if let Ok(b3) = three {
            if let Ok(c) = paper_formula(&b3, &ranges3) { prop_assert!(is_proper_finite(&c)); }
            if let Ok(sol) = SnapshotSolver::new(b3, BaselineCorrelation::independent()).solve(&ranges3) {
                prop_assert!(is_proper_finite(&sol.c_rb));
            }
        }
        if let Ok(b2) = two {
            let solver = SnapshotSolver::new(b2, BaselineCorrelation::shared_base_antenna());
            if let Ok(sol) = solver.solve(&ranges2) { prop_assert!(is_proper_finite(&sol.c_rb)); }
            let mut cfg = AmbiguityConfig::gps_l1(0.003, 0.3);
            cfg.max_nodes = 2000;
            let resolver = AmbiguityResolver::new(solver, cfg).unwrap();
            if let Ok(fix) = resolver.resolve(&phases) {
                prop_assert!(is_proper_finite(&fix.solution.c_rb));
                prop_assert!(fix.cost.is_finite());
            }
        }
    }
}
