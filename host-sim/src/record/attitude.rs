//! Attitude from a three-antenna recording: the prompts of the slaved antennas (one replica,
//! one clock: paper 003's eq. (19) outputs) give carrier-phase single differences, the
//! early/late taps give code single differences, and the core's constrained ambiguity resolver
//! (`attitude::ambiguity`, MC-LAMBDA objective with the known baselines, ratio and χ² tests)
//! with the snapshot solver (`attitude::snapshot`) turns each window into an attitude.
//!
//! Why this estimator for a recording: a short static recording has no motion for a filter to
//! exploit, the lines of sight come from a sky file rather than a navigation solution, and
//! every window must stand on its own (a refused window says so, a wrong one would be silent).
//! The one-stage filter of paper 003 needs a prior attitude within its pull-in range and
//! estimates one angle in the paper's set-up; the snapshot resolver needs neither.
//!
//! Per window of `W` seconds (default 1 s) and satellite (every epoch of the window locked):
//!
//! ```text
//! φ_i = arg(Σ_k P_i,k P*_0,k)/2π − β_i           cycles (β_i: --line-bias; data bits cancel)
//! p_i = (c/f_chip) · mean_k (D_i,k − D_0,k)        m, D = the normalized early-late
//!                                                   discriminator, averaged from the start
//!                                                   (static receiver)
//! ```
//! with `λ φ_i = μ·(C_rb b_i) + λ z_i` (μ the line of sight, NED). Noise levels per
//! satellite from its C/N0: `σ_φ = λ σ_Δφ(C/N0, 1 ms)/√n` (the exact phase-difference RMS)
//! with a 1 mm floor (multipath, residual biases), and `σ_p = (c/f_chip) √(1/(2 (C/N0) T) / n)`
//! (the normalized discriminator's variance `1/(4 (C/N0) T)` per antenna) with a 5 cm floor;
//! the resolver takes the best satellite's pair and cofactors `(σ_φ,j/σ_φ,best)²`.

use anyhow::{ensure, Result};
use gnss_attitude::attitude::ambiguity::{
    AmbiguityConfig, AmbiguityResolver, PhaseObservations, PhaseSatellite, GPS_L1_WAVELENGTH_M,
};
use gnss_attitude::attitude::range_model::{BaselineCorrelation, Baselines, MAX_SATELLITES};
use gnss_attitude::attitude::snapshot::SnapshotSolver;
use gnss_attitude::signal::CA_CHIP_RATE_HZ;
use gnss_attitude::tracking::loops::dll_chips;
use gnss_attitude::tracking::{ChannelConfig, TrackingEpoch};
use nalgebra::Vector3;
use serde::Serialize;

pub use super::attitude_setup::{parse_baselines, parse_sky, AttitudeSetup};
use super::satellite::SatTrack;
use crate::stats::phase_difference_rms_cycles;
use crate::synth::scene::SPEED_OF_LIGHT;

/// Metres per C/A chip.
pub const CHIP_M: f64 = SPEED_OF_LIGHT / CA_CHIP_RATE_HZ;

/// Floor of the single-difference phase noise, m.
pub const PHASE_SIGMA_FLOOR_M: f64 = 1e-3;

/// Floor of the single-difference code noise, m.
pub const CODE_SIGMA_FLOOR_M: f64 = 0.05;

/// One window's sums of a satellite.
#[derive(Clone, Copy, Debug)]
pub struct WindowSums {
    index: usize,
    sum: [[f64; 2]; 2],
    n: u32,
    all_locked: bool,
    cn0_dbhz: f64,
    code_mean_chips: [f64; 2],
    code_n: u64,
}

/// Per-satellite phase and code sums (fed by the tracker with every epoch).
#[derive(Clone, Debug)]
pub struct PhaseAccumulator {
    los: Option<Vector3<f64>>,
    window_s: f64,
    offset_chips: f32,
    current: WindowSums,
    code_sum: [f64; 2],
    done: Vec<WindowSums>,
}

impl PhaseAccumulator {
    /// Adds an epoch at time `t` (s); `locked`: code and phase lock.
    pub fn add<const A: usize>(&mut self, e: &TrackingEpoch<A>, t: f64, locked: bool) {
        let index = (t / self.window_s).floor() as usize;
        if index != self.current.index {
            self.close();
            self.current = WindowSums {
                index,
                sum: [[0.0; 2]; 2],
                n: 0,
                all_locked: true,
                cn0_dbhz: f64::NAN,
                code_mean_chips: [0.0; 2],
                code_n: self.current.code_n,
            };
        }
        let taps = &e.correlations.taps;
        if !locked || A < 3 {
            self.current.all_locked = false;
            return;
        }
        let p0 = taps[0].prompt;
        let d0 = dll_chips(&taps[0].early, &taps[0].late, self.offset_chips);
        for i in 0..2 {
            let p = taps[i + 1].prompt;
            // P_i P_0*
            let (a, b) = (f64::from(p.i), f64::from(p.q));
            let (c, d) = (f64::from(p0.i), f64::from(p0.q));
            self.current.sum[i][0] += a * c + b * d;
            self.current.sum[i][1] += b * c - a * d;
            let di = dll_chips(&taps[i + 1].early, &taps[i + 1].late, self.offset_chips);
            self.code_sum[i] += f64::from(di - d0);
        }
        self.current.n += 1;
        self.current.code_n += 1;
        self.current.cn0_dbhz = f64::from(e.cn0_dbhz);
    }

    /// Sets the line of sight (unit vector, NED) the next windows use (`None`: unknown,
    /// the satellite is left out).
    pub fn set_los(&mut self, los: Option<Vector3<f64>>) {
        self.los = los;
    }

    fn close(&mut self) {
        let mut w = self.current;
        if w.n > 0 {
            let n = w.code_n.max(1) as f64;
            w.code_mean_chips = self.code_sum.map(|s| s / n);
            self.done.push(w);
        }
    }

    fn take(&mut self, index: usize) -> Option<WindowSums> {
        if self.current.index == index && self.current.n > 0 {
            // The window ended with the stream.
            self.close();
            self.current.n = 0;
        }
        let found = self.done.iter().position(|w| w.index == index);
        let out = found.map(|k| self.done[k]);
        self.done.retain(|w| w.index > index);
        out
    }
}

/// One window's attitude (or the reason there is none).
#[derive(Clone, Debug, Serialize)]
pub struct WindowAttitude {
    /// Window start, s.
    pub t_start_s: f64,
    /// Window end, s.
    pub t_end_s: f64,
    /// Satellites used (locked through the window, in the sky file).
    pub satellites: Vec<u8>,
    /// The resolver's refusal or the reason no solution was tried (`None`: fixed).
    pub refused: Option<String>,
    /// Ratio of the second-best to the best candidate's cost (a lower bound when
    /// `ratio_lower_bound`).
    pub ratio: Option<f64>,
    /// No second candidate was found inside the search bound (the bound shrinks to the
    /// second-best cost in a second search of `max_nodes` nodes): `ratio` is a lower bound.
    pub ratio_lower_bound: Option<bool>,
    /// 3-2-1 yaw, pitch, roll (body to NED), degrees.
    pub ypr_deg: Option<[f64; 3]>,
    /// Their standard deviations, degrees.
    pub ypr_sigma_deg: Option<[f64; 3]>,
    /// RMS of the range-difference residuals, mm.
    pub residual_rms_mm: Option<f64>,
    /// Line biases of antennas 1 and 2 estimated in this window (without `--line-bias`),
    /// cycles in `[−½, ½)`.
    pub line_bias_cycles: Option<[f64; 2]>,
    /// Their standard deviations, cycles.
    pub line_bias_sigma_cycles: Option<[f64; 2]>,
}

/// The attitude part of the `track` report.
#[derive(Clone, Debug, Serialize)]
pub struct AttitudeReport {
    /// Estimator used.
    pub method: String,
    /// Window, s.
    pub window_s: f64,
    /// Windows tried.
    pub windows: usize,
    /// Windows with a validated fix.
    pub fixed: usize,
    /// Mean yaw, pitch, roll over the fixed windows, degrees.
    pub ypr_mean_deg: Option<[f64; 3]>,
    /// Standard deviation of yaw, pitch, roll over the fixed windows, degrees.
    pub ypr_std_deg: Option<[f64; 3]>,
    /// Mean formal standard deviation of yaw, pitch, roll, degrees.
    pub ypr_sigma_mean_deg: Option<[f64; 3]>,
    /// Line biases of antennas 1 and 2 (given with `--line-bias`, or the mean of the fixed
    /// windows' estimates), cycles.
    pub line_bias_cycles: Option<[f64; 2]>,
    /// Whether they were estimated (no `--line-bias`).
    pub line_bias_estimated: bool,
    /// Every window.
    pub per_window: Vec<WindowAttitude>,
}

/// The circular mean of the windows' line-bias estimates, cycles in `[−½, ½)`.
fn mean_bias(windows: &[WindowAttitude]) -> Option<[f64; 2]> {
    let est: Vec<[f64; 2]> = windows.iter().filter_map(|w| w.line_bias_cycles).collect();
    (!est.is_empty()).then(|| {
        std::array::from_fn(|i| {
            let tau = std::f64::consts::TAU;
            let (s, c) = est.iter().fold((0.0, 0.0), |(s, c), b| {
                (s + (tau * b[i]).sin(), c + (tau * b[i]).cos())
            });
            s.atan2(c) / tau
        })
    })
}

/// The attitude stage.
pub struct AttitudeSolver {
    setup: AttitudeSetup,
    snapshot: SnapshotSolver<2, f32>,
    offset_chips: f32,
}

impl AttitudeSolver {
    /// A solver for the set-up; the channel configuration gives the early/late offset.
    ///
    /// # Errors
    /// Degenerate baselines, a window outside 0.1–60 s.
    pub fn new(setup: &AttitudeSetup, fs: f64, config: &ChannelConfig) -> Result<Self> {
        ensure!(
            (0.1..=60.0).contains(&setup.window_s),
            "attitude window {} s: 0.1-60 s",
            setup.window_s
        );
        let b = setup
            .baselines_body_m
            .map(|v| Vector3::new(v[0] as f32, v[1] as f32, v[2] as f32));
        let baselines = Baselines::new(b)
            .map_err(|e| anyhow::anyhow!("--baselines {:?}: {e}", setup.baselines_body_m))?;
        let samples = (f64::from(config.early_late_offset_chips) * fs / CA_CHIP_RATE_HZ)
            .round()
            .max(1.0);
        Ok(Self {
            setup: setup.clone(),
            snapshot: SnapshotSolver::new(baselines, BaselineCorrelation::shared_base_antenna()),
            offset_chips: (samples * CA_CHIP_RATE_HZ / fs) as f32,
        })
    }

    /// Whether the lines of sight come from the navigation fixes (no sky file).
    pub fn uses_navigation(&self) -> bool {
        self.setup.sky.is_empty()
    }

    /// The accumulator of satellite `prn` (its line of sight from the sky file, NED; none
    /// yet without a sky file).
    pub fn accumulator(&self, prn: u8) -> PhaseAccumulator {
        let los = self
            .setup
            .sky
            .iter()
            .find(|s| s.0 == prn)
            .map(|&(_, az, el)| {
                let (a, e) = (az.to_radians(), el.to_radians());
                Vector3::new(e.cos() * a.cos(), e.cos() * a.sin(), -e.sin())
            });
        PhaseAccumulator {
            los,
            window_s: self.setup.window_s,
            offset_chips: self.offset_chips,
            current: WindowSums {
                index: 0,
                sum: [[0.0; 2]; 2],
                n: 0,
                all_locked: true,
                cn0_dbhz: f64::NAN,
                code_mean_chips: [0.0; 2],
                code_n: 0,
            },
            code_sum: [0.0; 2],
            done: Vec::new(),
        }
    }

    /// The window length, s.
    pub fn window_s(&self) -> f64 {
        self.setup.window_s
    }

    /// End of window `k`, s.
    pub fn window_end(&self, k: usize) -> f64 {
        (k + 1) as f64 * self.setup.window_s
    }

    /// Resolves window `k` from the satellites' sums.
    ///
    /// # Errors
    /// Only the resolver's set-up errors; refusals are reported in the window.
    pub fn solve_window<'a>(
        &self,
        k: usize,
        sats: impl Iterator<Item = &'a mut SatTrack>,
    ) -> Result<WindowAttitude> {
        let w = self.setup.window_s;
        let full = (0.9 * w * 1000.0) as u32;
        let lambda = GPS_L1_WAVELENGTH_M;
        // (prn, los, phase, code, σ_φ m, σ_p m, C/N0)
        let mut rows = Vec::new();
        for s in sats {
            let prn = s.prn();
            let Some(acc) = s.phases.as_mut() else {
                continue;
            };
            let Some(sums) = acc.take(k) else { continue };
            let Some(los) = acc.los else { continue };
            if !sums.all_locked || sums.n < full || !sums.cn0_dbhz.is_finite() {
                continue;
            }
            let phase: [f64; 2] = std::array::from_fn(|i| {
                let [re, im] = sums.sum[i];
                im.atan2(re) / std::f64::consts::TAU
                    - self.setup.line_bias_cycles.map_or(0.0, |b| b[i])
            });
            let code = sums.code_mean_chips.map(|c| c * CHIP_M);
            let n = f64::from(sums.n);
            let cn0 = 10f64.powf(sums.cn0_dbhz / 10.0);
            let sigma_phi = lambda * phase_difference_rms_cycles(sums.cn0_dbhz, 1e-3) / n.sqrt();
            let sigma_p = CHIP_M * (1.0 / (2.0 * cn0 * 1e-3) / sums.code_n.max(1) as f64).sqrt();
            rows.push((prn, los, phase, code, sigma_phi, sigma_p, sums.cn0_dbhz));
        }
        // The strongest satellites, if more than the resolver takes.
        rows.sort_by(|a, b| b.6.total_cmp(&a.6));
        rows.truncate(MAX_SATELLITES);
        let mut out = WindowAttitude {
            t_start_s: k as f64 * w,
            t_end_s: (k + 1) as f64 * w,
            satellites: rows.iter().map(|r| r.0).collect(),
            refused: None,
            ratio: None,
            ratio_lower_bound: None,
            ypr_deg: None,
            ypr_sigma_deg: None,
            residual_rms_mm: None,
            line_bias_cycles: None,
            line_bias_sigma_cycles: None,
        };
        out.satellites.sort_unstable();
        if rows.len() < 4 {
            out.refused = Some(format!(
                "{} satellites locked through the window with a line of sight (4 needed)",
                rows.len()
            ));
            return Ok(out);
        }
        let best_phi = rows.iter().map(|r| r.4).fold(f64::INFINITY, f64::min);
        let best_p = rows.iter().map(|r| r.5).fold(f64::INFINITY, f64::min);
        let mut obs = PhaseObservations::<2, MAX_SATELLITES, f32>::new();
        for r in &rows {
            obs.push(PhaseSatellite {
                id: r.0,
                los: r.1.cast::<f32>(),
                phase_cycles: r.2.map(|x| x as f32),
                code_m: r.3.map(|x| x as f32),
                cofactor: ((r.4 / best_phi).powi(2)) as f32,
            })
            .map_err(|e| anyhow::anyhow!("PRN {}: {e}", r.0))?;
        }
        let mut cfg = AmbiguityConfig::gps_l1(
            best_phi.max(PHASE_SIGMA_FLOOR_M) as f32,
            best_p.max(CODE_SIGMA_FLOOR_M) as f32,
        );
        cfg.max_nodes = 500_000;
        // The true ratio, not the threshold the first search pruned at.
        cfg.ratio_nodes = cfg.max_nodes;
        let resolver = AmbiguityResolver::new(self.snapshot, cfg)
            .map_err(|e| anyhow::anyhow!("ambiguity resolver: {e}"))?;
        let resolved = match self.setup.line_bias_cycles {
            Some(_) => resolver.resolve(&obs),
            None => resolver.resolve_with_line_biases(&obs).map(|b| {
                let wrap = |c: f32| f64::from(c) - f64::from(c).round();
                out.line_bias_cycles = Some(b.line_bias_cycles.map(wrap));
                out.line_bias_sigma_cycles = Some(b.line_bias_sigma_cycles.map(f64::from));
                b.fix
            }),
        };
        match resolved {
            Ok(fix) => {
                let e = fix.solution.euler;
                out.ratio = Some(f64::from(fix.ratio));
                out.ratio_lower_bound = Some(fix.ratio_is_lower_bound);
                out.ypr_deg = Some([e.yaw, e.pitch, e.roll].map(|a| f64::from(a).to_degrees()));
                out.ypr_sigma_deg = fix
                    .solution
                    .euler_std()
                    .map(|s| s.map(|a| f64::from(a).to_degrees()));
                out.residual_rms_mm = Some(f64::from(fix.solution.residual_rms) * 1e3);
            }
            Err(e) => out.refused = Some(e.to_string()),
        }
        Ok(out)
    }

    /// The summary of the windows.
    pub fn report(&self, windows: Vec<WindowAttitude>) -> AttitudeReport {
        // Yaw unwrapped around the first fix, so that a mean near ±180° is not 0.
        let mut fixed: Vec<[f64; 3]> = windows.iter().filter_map(|w| w.ypr_deg).collect();
        if let Some(first) = fixed.first().map(|f| f[0]) {
            for f in &mut fixed {
                f[0] -= 360.0 * ((f[0] - first) / 360.0).round();
            }
        }
        let sig: Vec<[f64; 3]> = windows.iter().filter_map(|w| w.ypr_sigma_deg).collect();
        let mean = |v: &[[f64; 3]]| -> Option<[f64; 3]> {
            (!v.is_empty()).then(|| {
                std::array::from_fn(|j| v.iter().map(|x| x[j]).sum::<f64>() / v.len() as f64)
            })
        };
        let m = mean(&fixed);
        let std = m.map(|m| {
            std::array::from_fn(|j| {
                (fixed.iter().map(|x| (x[j] - m[j]).powi(2)).sum::<f64>()
                    / (fixed.len().max(2) - 1) as f64)
                    .sqrt()
            })
        });
        AttitudeReport {
            method: if self.setup.line_bias_cycles.is_some() {
                "per-window single differences -> constrained integer ambiguity resolution (MC-LAMBDA objective, ratio 3, chi2 99.9 %) -> snapshot ML attitude (core, f32)"
            } else {
                "per-window double differences (line biases unknown) -> constrained integer ambiguity resolution (MC-LAMBDA objective, ratio 3, chi2 99.9 %) -> line biases and snapshot ML attitude (core, f32)"
            }
            .into(),
            window_s: self.setup.window_s,
            windows: windows.len(),
            fixed: fixed.len(),
            ypr_mean_deg: m,
            ypr_std_deg: std,
            ypr_sigma_mean_deg: mean(&sig),
            line_bias_cycles: self.setup.line_bias_cycles.or_else(|| mean_bias(&windows)),
            line_bias_estimated: self.setup.line_bias_cycles.is_none(),
            per_window: windows,
        }
    }
}
