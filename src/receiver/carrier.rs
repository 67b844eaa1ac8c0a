//! Window-level carrier-phase processing: the cold start (paper 002 with integer ambiguity
//! resolution), the snapshot monitor, the upkeep of the fixed ambiguities (cycle slips, new
//! satellites) against a trusted attitude, and the baselines and velocity differences the
//! rigid-body filter (paper 000) takes.

use nalgebra::{Matrix3, Vector3};

use crate::attitude::ambiguity::AmbiguityResolver;
use crate::attitude::baseline_epoch::BaselineEpoch;
use crate::attitude::range_model::{
    los_normal_matrix, PhaseObservations, PhaseSatellite, RangeDifferences, SatelliteRanges,
};
use crate::attitude::snapshot::{SnapshotQuality, SnapshotSolution, SnapshotSolver};

use super::satellite::WindowSd;
use super::MAX_SATELLITES;

/// One satellite's window with the index of its slot.
pub(crate) type Windowed = (usize, WindowSd);

/// The integers of the cold start: per satellite its slot and `K` of B and C.
pub(crate) type FixedSlots = heapless::Vec<(usize, [i32; 2]), MAX_SATELLITES>;

/// `a_B`, `a_C` (m) and their rates (m/s), reference frame.
pub(crate) type BaselinesAndRates = ([Vector3<f32>; 2], [Vector3<f32>; 2]);

/// The body baselines `A→B`, `A→C`, m.
pub(crate) fn body_baselines(antennas: &[Vector3<f32>; 3]) -> [Vector3<f32>; 2] {
    let [a, b, c] = antennas;
    [b - a, c - a]
}

/// The cold start: resolves the ambiguities of the satellites valid on both baselines.
/// Returns the fix's attitude (at the window's centre) and, per input satellite, its slot and
/// the integers `K` (`phase − K` is the geometric SD).
pub(crate) fn cold_start(
    resolver: &AmbiguityResolver<2, f32>,
    windows: &[Windowed],
    sigma_ref_cycles: f32,
) -> Option<(SnapshotSolution<f32>, FixedSlots)> {
    let mut obs = PhaseObservations::<2, MAX_SATELLITES, f32>::new();
    let mut slots = heapless::Vec::<usize, MAX_SATELLITES>::new();
    for (slot, w) in windows.iter().filter(|(_, w)| w.valid == [true, true]) {
        let ratio = w.sigma_cycles / sigma_ref_cycles;
        let sat = PhaseSatellite {
            id: w.prn,
            los: w.los,
            phase_cycles: w.phase,
            code_m: [0.0; 2],
            cofactor: (ratio * ratio).max(1e-4),
        };
        if obs.push(sat).is_ok() {
            let _ = slots.push(*slot);
        }
    }
    let fix = resolver.resolve(&obs).ok()?;
    let mut out = heapless::Vec::new();
    for (j, slot) in slots.iter().enumerate() {
        let k = [
            fix.ambiguities[0].get(j).copied().unwrap_or(0),
            fix.ambiguities[1].get(j).copied().unwrap_or(0),
        ];
        let _ = out.push((*slot, k));
    }
    Some((fix.solution, out))
}

/// The snapshot of the fixed satellites (range differences `λ(phase − K)`).
pub(crate) fn snapshot(
    solver: &SnapshotSolver<2, f32>,
    fixed: &[(WindowSd, [i32; 2])],
    wavelength_m: f32,
) -> Option<SnapshotSolution<f32>> {
    let mut rd = RangeDifferences::<2, MAX_SATELLITES, f32>::new();
    for (w, k) in fixed {
        let sat = SatelliteRanges {
            id: w.prn,
            los: w.los,
            range_diff: [
                wavelength_m * (w.phase[0] - k[0] as f32),
                wavelength_m * (w.phase[1] - k[1] as f32),
            ],
            sigma: wavelength_m * w.sigma_cycles.max(1e-4),
        };
        let _ = rd.push(sat);
    }
    let s = solver.solve(&rd).ok()?;
    (s.quality == SnapshotQuality::Good).then_some(s)
}

/// The single difference (cycles) `b_Pᵀ C_rbᵀ μ / λ` predicted for baseline `k` (0 = B, 1 = C).
pub(crate) fn predicted_sd(
    c_rb: &Matrix3<f32>,
    baselines: &[Vector3<f32>; 2],
    k: usize,
    los: &Vector3<f32>,
    wavelength_m: f32,
) -> f32 {
    baselines
        .get(k)
        .map_or(0.0, |b| (c_rb * b).dot(los) / wavelength_m)
}

/// Weighted least squares of the reference-frame baselines `a_B`, `a_C` (m) from the fixed
/// window SDs, and of their rates (m/s) from the SD rates minus the line-of-sight motion
/// `a · μ̇` (velocity differences `V_P − V_A`). Needs three non-coplanar lines of sight.
pub(crate) fn baselines_and_velocities(
    fixed: &[(WindowSd, [i32; 2], Vector3<f32>)],
    wavelength_m: f32,
) -> Option<BaselinesAndRates> {
    let weights = fixed
        .iter()
        .map(|(w, _, _)| (w.los, 1.0 / (w.sigma_cycles * w.sigma_cycles).max(1e-10)));
    let (_, n_inv) = los_normal_matrix(weights).ok()?;
    let mut a = [Vector3::zeros(); 2];
    for (k, ak) in a.iter_mut().enumerate() {
        let mut rhs = Vector3::zeros();
        for (w, kk, _) in fixed {
            let weight = 1.0 / (w.sigma_cycles * w.sigma_cycles).max(1e-10);
            let r = wavelength_m
                * (w.phase.get(k).copied().unwrap_or(0.0) - kk.get(k).copied().unwrap_or(0) as f32);
            rhs += w.los * (weight * r);
        }
        *ak = n_inv * rhs;
    }
    let mut v = [Vector3::zeros(); 2];
    for (k, vk) in v.iter_mut().enumerate() {
        let ak = a.get(k).copied().unwrap_or_else(Vector3::zeros);
        let mut rhs = Vector3::zeros();
        for (w, _, los_rate) in fixed {
            let weight = 1.0 / (w.sigma_cycles * w.sigma_cycles).max(1e-10);
            // d/dt (a·μ) = ȧ·μ + a·μ̇
            let r = wavelength_m * w.rate.get(k).copied().unwrap_or(0.0) - ak.dot(los_rate);
            rhs += w.los * (weight * r);
        }
        *vk = n_inv * rhs;
    }
    let finite = a
        .iter()
        .chain(v.iter())
        .all(|x| x.iter().all(|e| e.is_finite()));
    finite.then_some((a, v))
}

/// The rigid-body filter's epoch: baselines `b₁₂ = r_A − r_B = −a_B`, `b₁₃ = −a_C` at the
/// window's end (extrapolated from its centre by half a window of the velocity difference)
/// and the velocity differences over the window. `b₂₃` is left out: it is the difference of
/// the other two and would count their noise twice.
pub(crate) fn baseline_epoch(
    a: &[Vector3<f32>; 2],
    v: &[Vector3<f32>; 2],
    half_window_s: f32,
) -> BaselineEpoch<f32> {
    let [ab, ac] = a;
    let [vb, vc] = v;
    let mut e = BaselineEpoch::default();
    e.baselines[0] = Some(-(ab + vb * half_window_s));
    e.baselines[2] = Some(-(ac + vc * half_window_s));
    e.velocity_differences[0] = Some(-vb);
    e.velocity_differences[2] = Some(-vc);
    e
}
