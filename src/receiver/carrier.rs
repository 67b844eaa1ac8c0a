//! Window-level carrier-phase processing: the cold start (paper 002 with integer ambiguity
//! resolution), the snapshot monitor, the upkeep of the fixed ambiguities (cycle slips, new
//! satellites) against a trusted attitude, and the baselines and velocity differences the
//! rigid-body filter (paper 000) takes.
//!
//! Every window SD here is in cycles with the line biases still in; `geometric(w, K, β)`
//! removes both: `φ − β/2π − K`.

use heapless::Vec;
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

/// The integers of a fix: per satellite its slot and `K` of B and C.
pub(crate) type FixedSlots = Vec<(usize, [i32; 2]), MAX_SATELLITES>;

/// A fixed window: the window, its integers and the line of sight's rate (1/s).
pub(crate) type FixedWindow = (WindowSd, [i32; 2], Vector3<f32>);

/// `a_B`, `a_C` (m) and their rates (m/s), reference frame.
pub(crate) type BaselinesAndRates = ([Vector3<f32>; 2], [Vector3<f32>; 2]);

/// Smallest cofactor of a satellite in the cold start (its σ relative to the reference).
const MIN_COFACTOR: f32 = 1e-4;

/// Smallest window SD σ the snapshot and the least squares use, cycles.
const MIN_SIGMA_CYCLES: f32 = 1e-4;

/// The body baselines `A→B`, `A→C`, m.
pub(crate) fn body_baselines(antennas: &[Vector3<f32>; 3]) -> [Vector3<f32>; 2] {
    let [a, b, c] = antennas;
    [b - a, c - a]
}

/// The window SDs of both baselines with the line biases `beta_cycles` removed (the integers
/// kept), cycles.
pub(crate) fn unbiased(w: &WindowSd, beta_cycles: &[f32; 2]) -> [f32; 2] {
    let [b, c] = w.phase;
    [b - beta_cycles[0], c - beta_cycles[1]]
}

/// What a cold start (or the integrity check's fresh fix) gives.
pub(crate) struct ColdFix {
    /// The attitude at the window's centre.
    pub solution: SnapshotSolution<f32>,
    /// Per satellite used, its slot and the integers `K` (`φ − β/2π − K` geometric).
    pub slots: FixedSlots,
    /// The line biases resolved with the integers, cycles, and their σ (`None` when they
    /// were given).
    pub line_bias: Option<([f32; 2], [f32; 2])>,
}

/// The cold start: resolves the ambiguities of the satellites valid on both baselines. With
/// the line biases known (`Some`, cycles) they are removed and the single differences
/// resolved; unknown (`None`), the double differences are, and the biases come back with the
/// fix.
#[cfg_attr(feature = "optimize-cold", optimize(size))]
pub(crate) fn cold_start(
    resolver: &AmbiguityResolver<2, f32>,
    windows: &[Windowed],
    sigma_ref_cycles: f32,
    beta_cycles: Option<[f32; 2]>,
) -> Option<ColdFix> {
    let removed = beta_cycles.unwrap_or([0.0; 2]);
    let mut obs = PhaseObservations::<2, MAX_SATELLITES, f32>::new();
    let mut slots = Vec::<usize, MAX_SATELLITES>::new();
    for (slot, w) in windows.iter().filter(|(_, w)| w.valid == [true, true]) {
        let ratio = w.sigma_cycles / sigma_ref_cycles;
        let sat = PhaseSatellite {
            id: w.prn,
            los: w.los,
            phase_cycles: unbiased(w, &removed),
            code_m: [0.0; 2],
            cofactor: (ratio * ratio).max(MIN_COFACTOR),
        };
        // both hold at most MAX_SATELLITES: a refused satellite stops the collection
        if obs.push(sat).is_err() || slots.push(*slot).is_err() {
            break;
        }
    }
    // (a resolved bias carries the reference satellite's whole cycles: they move into the
    // integers, so that the bias is a fraction of a cycle)
    let (fix, line_bias, whole) = match beta_cycles {
        Some(_) => (resolver.resolve(&obs).ok()?, None, [0; 2]),
        None => {
            let f = resolver.resolve_with_line_biases(&obs).ok()?;
            let [b, c] = f.line_bias_cycles;
            let whole = [libm::roundf(b) as i32, libm::roundf(c) as i32];
            let fraction = [b - whole[0] as f32, c - whole[1] as f32];
            (f.fix, Some((fraction, f.line_bias_sigma_cycles)), whole)
        }
    };
    let mut out = Vec::new();
    // (indices from a range, not `enumerate`: its counter keeps an overflow check)
    for (j, slot) in (0..slots.len()).zip(slots.iter()) {
        let k = [
            fix.ambiguities[0].get(j).copied()?.saturating_add(whole[0]),
            fix.ambiguities[1].get(j).copied()?.saturating_add(whole[1]),
        ];
        out.push((*slot, k)).ok()?;
    }
    Some(ColdFix {
        solution: fix.solution,
        slots: out,
        line_bias,
    })
}

/// The snapshot of the fixed satellites (range differences `λ(φ − β/2π − K)`).
pub(crate) fn snapshot(
    solver: &SnapshotSolver<2, f32>,
    fixed: &[FixedWindow],
    wavelength_m: f32,
    beta_cycles: &[f32; 2],
) -> Option<SnapshotSolution<f32>> {
    let mut rd = RangeDifferences::<2, MAX_SATELLITES, f32>::new();
    for (w, k, _) in fixed {
        let sat = SatelliteRanges {
            id: w.prn,
            los: w.los,
            range_diff: {
                let [pb, pc] = unbiased(w, beta_cycles);
                [
                    wavelength_m * (pb - k[0] as f32),
                    wavelength_m * (pc - k[1] as f32),
                ]
            },
            sigma: wavelength_m * w.sigma_cycles.max(MIN_SIGMA_CYCLES),
        };
        rd.push(sat).ok()?;
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

/// Weight of a window SD in the least squares, 1/cycles².
fn weight(w: &WindowSd) -> f32 {
    let s = w.sigma_cycles.max(MIN_SIGMA_CYCLES);
    1.0 / (s * s)
}

/// Weighted least squares of the reference-frame baselines `a_B`, `a_C` (m) from the fixed
/// window SDs, and of their rates (m/s) from the SD rates minus the line-of-sight motion
/// `a · μ̇` (velocity differences `V_P − V_A`). Needs three non-coplanar lines of sight.
pub(crate) fn baselines_and_velocities(
    fixed: &[FixedWindow],
    wavelength_m: f32,
    beta_cycles: &[f32; 2],
) -> Option<BaselinesAndRates> {
    let (_, n_inv) = los_normal_matrix(fixed.iter().map(|(w, _, _)| (w.los, weight(w)))).ok()?;
    let mut a = [Vector3::zeros(); 2];
    let mut v = [Vector3::zeros(); 2];
    for k in 0..2 {
        let mut rhs = Vector3::zeros();
        for (w, kk, _) in fixed {
            let r = wavelength_m * (unbiased(w, beta_cycles)[k] - kk[k] as f32);
            rhs += w.los * (weight(w) * r);
        }
        a[k] = n_inv * rhs;
        let mut rhs = Vector3::zeros();
        for (w, _, los_rate) in fixed {
            // d/dt (a·μ) = ȧ·μ + a·μ̇
            let r = wavelength_m * w.rate[k] - a[k].dot(los_rate);
            rhs += w.los * (weight(w) * r);
        }
        v[k] = n_inv * rhs;
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
