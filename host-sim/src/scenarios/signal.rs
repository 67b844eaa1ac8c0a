//! `signal`: the fixed-point three-antenna GPS L1 C/A signal chain on synthesized samples.
//!
//! Scene: eight satellites in paper 003's geometry G1 (azimuth 45°·(i−1), elevation 10°·i),
//! all at the variant's C/N0, Dopplers within ±4.5 kHz and Doppler rates within ±0.8 Hz/s,
//! 50 bit/s data; paper 003's array (equilateral triangle, side 1.5 m, origin at the middle of
//! AB) turning about the body Y axis at 0.01 rad/s; line biases 0, 0.13, −0.27 cycle; complex
//! CS8 samples at 2.6 Msps (noise σ = 16 LSB). The chain: acquisition of all 32 PRNs on the
//! reference antenna (40 ms, ±10 kHz in 500 Hz bins, P_fa = 10⁻⁵ per PRN), then tracking of
//! the detected ones for 61 s (so that lock can be held for 60 s after pull-in).
//!
//! Metrics: `prn_chips_ok` (core codes matching IS-GPS-200's first 10 chips, of 32),
//! `acq_found` / `acq_missed` / `acq_false` (over the visible satellites; false = a detected
//! PRN that is not in the scene), `doppler_err_hz_max` and `code_err_chips_max` (acquisition
//! against the truth), `lock_held_s` (minimum over satellites of the longest stretch with
//! code and phase lock), `cn0_err_db_max` (every 1 s C/N0 report from 2 s on, against the
//! synthesized C/N0), `phase_diff_err_rms_cycles` (the carrier-phase differences of antennas
//! B and C against A from the prompts, `arg(P_X P_A*)`, against the synthesized geometry and
//! line biases, from 2 s on) and `phase_diff_bound_cycles` (the theoretical RMS of that
//! difference for two independent prompts at SNR = (C/N0)·T, computed exactly from the phase
//! density of a noisy phasor, not the high-SNR approximation).

use std::collections::BTreeMap;
use std::f64::consts::TAU;

use anyhow::Result;
use gnss_attitude::signal::{Prn, SampleFormat};
use gnss_attitude::tracking::{AcquisitionConfig, ChannelConfig};
use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use super::{Outcome, RunContext, Scenario, Variant, Variants};
use crate::arrays::triangle;
use crate::chain::{self, ChainOutput, ChainParams};
use crate::open_loop::{open_loop_losses, OpenLoopLosses, OPEN_LOOP_EPOCHS};
use crate::report::{plot_panels, progress, write_csv, Panel, Series};
use crate::stats::phase_difference_rms_cycles;
use crate::synth::file::{read_streams, write_streams};
use crate::synth::quantize::{encode, Quantizer};
use crate::synth::{AttitudeMotion, FrontEnd, Satellite, Scene};

/// The scenario.
pub const SCENARIO: Scenario = Scenario {
    name: "signal",
    about: "fixed-point 3-antenna GPS L1 C/A chain on synthesized samples: acquisition, 60 s tracking, C/N0, phase differences",
    variants: &Variants {
        list: &[
            Variant::new("40dbhz", "8 satellites at 40 dB-Hz", 40.0),
            Variant::new("35dbhz", "8 satellites at 35 dB-Hz", 35.0),
            Variant::new("45dbhz", "8 satellites at 45 dB-Hz", 45.0),
        ],
        run: |&cn0_dbhz, ctx| run(cn0_dbhz, ctx),
    },
};

/// Sample rate, Hz.
pub const SAMPLE_RATE_HZ: f64 = 2.6e6;
/// Tracking duration, s.
pub const DURATION_S: f64 = 61.0;
/// PRNs of the eight satellites.
pub const PRNS: [u8; 8] = [2, 5, 9, 12, 17, 21, 25, 30];
/// IS-GPS-200 Table 3-Ia, first 10 chips (octal), PRN 1–32.
pub const FIRST_TEN_CHIPS_OCTAL: [u16; 32] = [
    0o1440, 0o1620, 0o1710, 0o1744, 0o1133, 0o1455, 0o1131, 0o1454, 0o1626, 0o1504, 0o1642, 0o1750,
    0o1764, 0o1772, 0o1775, 0o1776, 0o1156, 0o1467, 0o1633, 0o1715, 0o1746, 0o1763, 0o1063, 0o1706,
    0o1743, 0o1761, 0o1770, 0o1774, 0o1127, 0o1453, 0o1625, 0o1712,
];

/// The scene of the scenario at `cn0_dbhz`.
pub fn scene(cn0_dbhz: f64, seed: u64) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let satellites = PRNS
        .iter()
        .enumerate()
        .map(|(k, &prn)| {
            let az = (45.0 * k as f64).to_radians();
            let el = (10.0 * (k + 1) as f64).to_radians();
            Satellite {
                prn,
                cn0_dbhz,
                doppler_hz: rng.random_range(-4500.0..4500.0),
                doppler_rate_hz_s: rng.random_range(-0.8..0.8),
                code_phase_chips: rng.random_range(0.0..1023.0),
                carrier_phase_cycles: rng.random_range(0.0..1.0),
                // Local frame: x north, y east, z up.
                los_ref: Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin()),
                data_seed: Some(seed.wrapping_mul(31).wrapping_add(k as u64)),
                track: None,
            }
        })
        .collect();
    Scene {
        satellites,
        antennas_b: triangle(1.5),
        line_bias_cycles: vec![0.0, 0.13, -0.27],
        attitude: AttitudeMotion::ConstantRate {
            c_rb0: Matrix3::identity(),
            omega_b: Vector3::new(0.0, 0.01, 0.0),
        },
        front_end: FrontEnd {
            sample_rate_hz: SAMPLE_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            complex: true,
        },
        noise_seed: Some(seed ^ 0x005e_ed0f_5167),
    }
}

/// The chain set-up of the scenario (CS8 front end; set `quantizer` for another).
pub fn params(cn0_dbhz: f64, seed: u64, duration_s: f64) -> ChainParams {
    ChainParams {
        scene: scene(cn0_dbhz, seed),
        format: SampleFormat::Cs8,
        quantizer: Quantizer::I8,
        acquisition: AcquisitionConfig {
            sample_rate_hz: SAMPLE_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 10_000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 40,
            // The threshold's Gamma model holds for noise only; the cross-correlation of eight
            // 45 dB-Hz satellites fattens the tail (at 10⁻³ one absent PRN crossed it), so
            // the scenario asks for 10⁻⁵ (threshold 2.35 instead of 2.15).
            false_alarm_probability: 1e-5,
        },
        search_prns: (1..=32).collect(),
        channel: ChannelConfig::new(SAMPLE_RATE_HZ, 0.0),
        duration_s,
        block: 32_768,
    }
}

fn wrap(x: f64) -> f64 {
    x - x.round()
}

crate::metrics! {
    /// Metrics of `signal`.
    pub struct Metrics {
        /// PRN codes whose first 10 chips match IS-GPS-200 (of 32).
        #[metric(unit = "")] pub prn_chips_ok: usize,
        /// Visible satellites acquired.
        #[metric(unit = "")] pub acq_found: usize,
        /// Visible satellites not acquired.
        #[metric(unit = "")] pub acq_missed: usize,
        /// Detected PRNs that are not in the scene.
        #[metric(unit = "")] pub acq_false: usize,
        /// Largest acquisition Doppler error against the truth.
        #[metric(unit = "Hz")] pub doppler_err_hz_max: f64,
        /// Largest acquisition code-phase error against the truth.
        #[metric(unit = "chip")] pub code_err_chips_max: f64,
        /// Shortest over the satellites of the longest stretch with code and phase lock.
        #[metric(unit = "s")] pub lock_held_s: f64,
        /// Largest error of the 1 s C/N0 reports (from 2 s on) against the synthesized C/N0.
        #[metric(unit = "dB")] pub cn0_err_db_max: f64,
        /// RMS error of the inter-antenna carrier-phase differences from the prompts.
        #[metric(unit = "cycle")] pub phase_diff_err_rms_cycles: f64,
        /// Theoretical RMS of that difference for two independent prompts (thermal noise).
        #[metric(unit = "cycle")] pub phase_diff_bound_cycles: f64,
        /// The front end the samples went through (`--front-end`): `i8` (CS8), `sm2`, `bit1`.
        #[metric(unit = "")] pub front_end: &'static str,
        /// The tracking channels' C/N0 estimates averaged over the locked epochs from 2 s on,
        /// then over the satellites.
        #[metric(unit = "dB-Hz")] pub cn0_mean_dbhz: f64,
        /// C/N0 loss of the front end: the `i8` run's `cn0_mean_dbhz` on the same synthesized
        /// signals (same seed) minus this run's, over the satellites both tracked (null for
        /// `i8`, the reference).
        #[metric(unit = "dB")] pub cn0_loss_db: Option<f64>,
        /// The open-loop correlator experiment on this front end's samples (`sm2`, `bit1`).
        #[metric(flatten)] #[serde(flatten)] pub open_loop: Option<OpenLoopLosses>,
    }
}

/// The PRNs of the GPS constellation the chain searches and checks.
const PRN_COUNT: u8 = 32;
/// Chips per code period.
const CODE_CHIPS: f64 = 1023.0;
/// Half a code period, chips (wraps code-phase errors into ±511.5).
const HALF_CODE_CHIPS: f64 = CODE_CHIPS / 2.0;
/// Coherent integration of one prompt, s.
const PROMPT_S: f64 = 1e-3;
/// Statistics start after the pull-in, s.
const SETTLED_S: f64 = 2.0;
/// Code periods between two C/N0 reports (the estimator reports once per second).
const CN0_REPORT_EPOCHS: usize = 1000;

/// Largest acquisition Doppler and code-phase errors against the truth.
fn acquisition_errors(out: &ChainOutput, sc: &Scene) -> (f64, f64) {
    let (mut doppler_max, mut code_max) = (0.0f64, 0.0f64);
    for t in &out.tracked {
        let truth = sc.truth(t.scene_index, 0, 0.0);
        doppler_max =
            doppler_max.max((f64::from(t.acquisition.doppler_hz) - truth.doppler_hz).abs());
        let e = (f64::from(t.acquisition.code_phase_chips) - truth.code_phase_chips
            + HALF_CODE_CHIPS)
            .rem_euclid(CODE_CHIPS)
            - HALF_CODE_CHIPS;
        code_max = code_max.max(e.abs());
    }
    (doppler_max, code_max)
}

/// The receiver sees C/(N0 + I0): the other satellites' multiple-access interference, dB.
/// Each leaks SNR_j · E|ρ|² ≈ SNR_j/1023 of noise power into a prompt (Gold-code
/// cross-correlation). Returns `(I0/N0, dB)`.
fn interference(cn0: f64, satellites: usize) -> (f64, f64) {
    let snr = 10f64.powf(cn0 / 10.0) * PROMPT_S;
    let interference = (satellites as f64 - 1.0) * snr / CODE_CHIPS;
    (interference, 10.0 * (1.0 + interference).log10())
}

/// Each tracked satellite's C/N0 estimates averaged over its locked epochs from
/// `SETTLED_S` (2 s) on, dB-Hz, by PRN (satellites never locked there are left out).
pub fn cn0_after_lock(out: &ChainOutput) -> BTreeMap<u8, f64> {
    out.tracked
        .iter()
        .filter_map(|t| {
            let v: Vec<f64> = t
                .epochs
                .iter()
                .filter(|e| e.locked && e.t >= SETTLED_S)
                .map(|e| e.cn0_dbhz)
                .collect();
            (!v.is_empty()).then(|| {
                (
                    t.acquisition.prn.number(),
                    v.iter().sum::<f64>() / v.len() as f64,
                )
            })
        })
        .collect()
}

/// The mean over the satellites of [`cn0_after_lock`], dB-Hz (NaN without one).
pub fn mean_cn0(per_prn: &BTreeMap<u8, f64>) -> f64 {
    per_prn.values().sum::<f64>() / per_prn.len() as f64
}

/// C/N0 loss of a front end against the reference: the mean over the satellites both
/// tracked of reference minus front end, dB (`None` without a common satellite).
pub fn cn0_loss_db(reference: &BTreeMap<u8, f64>, front_end: &BTreeMap<u8, f64>) -> Option<f64> {
    let d: Vec<f64> = reference
        .iter()
        .filter_map(|(prn, r)| front_end.get(prn).map(|f| r - f))
        .collect();
    (!d.is_empty()).then(|| d.iter().sum::<f64>() / d.len() as f64)
}

/// What the front end changes: its name, its C/N0 against the `i8` run, the open-loop losses.
struct FrontEndFigures {
    name: &'static str,
    cn0_mean: f64,
    cn0_loss: Option<f64>,
    open_loop: Option<OpenLoopLosses>,
}

fn metrics(
    out: &ChainOutput,
    sc: &Scene,
    cn0: f64,
    stats: &[SatStats],
    fe: FrontEndFigures,
) -> Metrics {
    let prn_chips_ok = (1..=PRN_COUNT)
        .filter(|&n| {
            Prn::new(n)
                .is_some_and(|p| p.first_ten_chips_octal() == FIRST_TEN_CHIPS_OCTAL[n as usize - 1])
        })
        .count();
    let (doppler_max, code_max) = acquisition_errors(out, sc);
    let lock_held = if out.tracked.len() < sc.satellites.len() {
        0.0
    } else {
        stats
            .iter()
            .map(|s| s.lock_held_s)
            .fold(f64::INFINITY, f64::min)
    };
    let (sum2, count) = stats.iter().fold((0.0, 0usize), |a, s| {
        (a.0 + s.phase_sum2, a.1 + s.phase_count)
    });
    Metrics {
        prn_chips_ok,
        acq_found: out.tracked.len(),
        acq_missed: sc.satellites.len() - out.tracked.len(),
        acq_false: out.false_detections.len(),
        doppler_err_hz_max: doppler_max,
        code_err_chips_max: code_max,
        lock_held_s: lock_held,
        cn0_err_db_max: stats.iter().map(|s| s.cn0_err_max).fold(0.0, f64::max),
        phase_diff_err_rms_cycles: if count > 0 {
            (sum2 / count as f64).sqrt()
        } else {
            f64::NAN
        },
        phase_diff_bound_cycles: phase_difference_rms_cycles(cn0, PROMPT_S),
        front_end: fe.name,
        cn0_mean_dbhz: fe.cn0_mean,
        cn0_loss_db: fe.cn0_loss,
        open_loop: fe.open_loop,
    }
}

fn summary(out: &ChainOutput, sc: &Scene, cn0: f64, stats: &[SatStats]) -> Vec<String> {
    let (interference, mai_db) = interference(cn0, sc.satellites.len());
    let bound = phase_difference_rms_cycles(cn0, PROMPT_S);
    let bound_mai = phase_difference_rms_cycles(cn0 - mai_db, PROMPT_S);
    let cn0_err_mai = stats
        .iter()
        .map(|s| s.cn0_err_max_vs(cn0 - mai_db))
        .fold(0.0, f64::max);
    let mut lines = vec![
        format!(
            "{} satellites at {cn0} dB-Hz, 2.6 Msps, 3 antennas; wall time: acquisition of 32 PRNs {:.1} s, synthesis of {DURATION_S} s of samples {:.1} s, tracking {:.1} s",
            sc.satellites.len(),
            out.acquisition_seconds,
            out.synthesis_seconds,
            out.tracking_seconds
        ),
        format!(
            "C/N0 error against C/(N0 + I0) = {:.2} dB-Hz (what a prompt/noise-tap estimator measures): max {cn0_err_mai:.2} dB",
            cn0 - mai_db
        ),
        format!(
            "multiple-access interference of the other satellites: I0/N0 = {interference:.3} ({mai_db:.2} dB below the thermal C/N0); phase-difference bound with it {bound_mai:.4} cycle (thermal only {bound:.4})"
        ),
    ];
    for s in stats {
        lines.push(format!(
            "PRN {:2}: lock held {:.2} s (from {:.2} s), C/N0 mean {:.2} dB-Hz (max error {:.2} dB), phase-difference error RMS {:.4} cycle",
            s.prn,
            s.lock_held_s,
            s.first_lock_s,
            s.cn0_mean,
            s.cn0_err_max,
            (s.phase_sum2 / s.phase_count.max(1) as f64).sqrt()
        ));
    }
    lines
}

/// The front end's figures: for `sm2` and `bit1` the same scene through the `i8` front end
/// (the C/N0 reference) and the open-loop experiment.
fn front_end_figures(
    params: &ChainParams,
    out: &ChainOutput,
    cn0: f64,
    seed: u64,
) -> Result<FrontEndFigures> {
    let own = cn0_after_lock(out);
    let mut fe = FrontEndFigures {
        name: params.quantizer.name(),
        cn0_mean: mean_cn0(&own),
        cn0_loss: None,
        open_loop: None,
    };
    if params.quantizer != Quantizer::I8 {
        let reference = ChainParams {
            quantizer: Quantizer::I8,
            ..params.clone()
        };
        let bar = progress(1000, "signal chain, i8 reference");
        let out_i8 = chain::run(&reference, Some(&bar))?;
        bar.finish_and_clear();
        fe.cn0_loss = cn0_loss_db(&cn0_after_lock(&out_i8), &own);
        fe.open_loop = Some(open_loop_losses(
            params.quantizer,
            cn0,
            seed,
            OPEN_LOOP_EPOCHS,
        )?);
    }
    Ok(fe)
}

fn run(cn0: f64, ctx: &RunContext) -> Result<Outcome> {
    let params = ChainParams {
        quantizer: ctx.front_end,
        ..params(cn0, ctx.seed, DURATION_S)
    };
    let bar = progress(1000, "signal chain");
    let out = chain::run(&params, Some(&bar))?;
    bar.finish_and_clear();
    let sc = &params.scene;
    let stats = satellite_stats(&out, sc, cn0);
    let fe = front_end_figures(&params, &out, cn0, ctx.seed)?;
    let mut o = Outcome::new(&metrics(&out, sc, cn0, &stats, fe))?;
    o.paper = json!({
        "note": "no paper figure for this chain; the issue's acceptance targets",
        "prn_chips_ok": 32, "acq_missed": 0, "acq_false": 0,
        "doppler_err_hz_max": 250.0, "code_err_chips_max": 0.5, "lock_held_s": 60.0,
        "cn0_err_db_max": 1.5, "phase_diff_err_rms_cycles": "≈ phase_diff_bound_cycles",
    });
    o.summary = summary(&out, sc, cn0, &stats);
    o.summary.push(front_end_line(&o, params.quantizer));
    if let Some(dir) = &ctx.out_dir {
        write_files(dir, &params, &out, &mut o, cn0)?;
    }
    Ok(o)
}

/// The summary line of the front end: its name, C/N0 and losses.
fn front_end_line(o: &Outcome, q: Quantizer) -> String {
    let num = |k: &str| o.metrics.get(k).and_then(serde_json::Value::as_f64);
    let mut line = format!(
        "front end {q}: C/N0 after lock {:.2} dB-Hz (mean over satellites)",
        num("cn0_mean_dbhz").unwrap_or(f64::NAN)
    );
    if let Some(loss) = num("cn0_loss_db") {
        line.push_str(&format!(
            "; loss against CS8 on the same signals: tracking (bit-parallel, 3-level carrier) {loss:.2} dB; open loop: samples {:.2} dB, bit-parallel carrier 2-level {:.2} dB, 3-level {:.2} dB",
            num("open_loop_sample_loss_db").unwrap_or(f64::NAN),
            num("open_loop_carrier_loss_db_2level").unwrap_or(f64::NAN),
            num("open_loop_carrier_loss_db_3level").unwrap_or(f64::NAN),
        ));
    }
    line
}

struct SatStats {
    prn: u8,
    cn0_reports: Vec<f64>,
    lock_held_s: f64,
    first_lock_s: f64,
    cn0_err_max: f64,
    cn0_mean: f64,
    phase_sum2: f64,
    phase_count: usize,
    per_second: Vec<[f64; 5]>,
}

impl SatStats {
    fn cn0_err_max_vs(&self, reference: f64) -> f64 {
        self.cn0_reports
            .iter()
            .map(|c| (c - reference).abs())
            .fold(0.0, f64::max)
    }
}

/// The longest stretch with code and phase lock, and the time of the first lock, s.
fn lock_stretch(epochs: &[crate::chain::EpochRecord]) -> (f64, f64) {
    let (mut best, mut run_start, mut first_lock) = (0.0f64, None::<f64>, f64::NAN);
    for e in epochs {
        match (e.locked, run_start) {
            (true, None) => {
                run_start = Some(e.t);
                if first_lock.is_nan() {
                    first_lock = e.t;
                }
            }
            (false, Some(s)) => {
                best = best.max(e.t - s);
                run_start = None;
            }
            _ => {}
        }
    }
    if let (Some(s), Some(last)) = (run_start, epochs.last()) {
        best = best.max(last.t + 0.5 * PROMPT_S - s);
    }
    (best, first_lock)
}

/// Sums over the settled epochs of one satellite: C/N0 reports, phase-difference errors, and
/// the per-second rows of the CSV.
#[derive(Default)]
struct Settled {
    cn0_err: f64,
    cn0_sum: f64,
    cn0_n: usize,
    sum2: f64,
    count: usize,
    per_second: Vec<[f64; 5]>,
}

fn settled(t: &crate::chain::TrackedSatellite, sc: &Scene, cn0: f64) -> Settled {
    let k = t.scene_index;
    let mut acc = Settled::default();
    // (sum of squared errors, count, second) of the current second
    let mut second = (0.0, 0usize, SETTLED_S);
    for (j, e) in t.epochs.iter().enumerate() {
        if e.t < SETTLED_S {
            continue;
        }
        // C/N0 reports change once per second: sample them once per 1000 epochs.
        if j % CN0_REPORT_EPOCHS == 0 {
            acc.cn0_err = acc.cn0_err.max((e.cn0_dbhz - cn0).abs());
            acc.cn0_sum += e.cn0_dbhz;
            acc.cn0_n += 1;
        }
        if e.t.floor() > second.2 && second.1 > 0 {
            let doppler_err = e.doppler_hz - sc.truth(k, 0, e.t).doppler_hz;
            acc.per_second.push([
                second.2 + 1.0,
                f64::from(t.acquisition.prn.number()),
                e.cn0_dbhz,
                doppler_err,
                (second.0 / second.1 as f64).sqrt(),
            ]);
            second = (0.0, 0, e.t.floor());
        }
        let a = e.prompt[0];
        for x in 1..3 {
            let b = e.prompt[x];
            let measured = (b.1 * a.0 - b.0 * a.1).atan2(b.0 * a.0 + b.1 * a.1) / TAU;
            let truth =
                sc.truth(k, x, e.t).carrier_phase_cycles - sc.truth(k, 0, e.t).carrier_phase_cycles;
            let err = wrap(measured - truth);
            acc.sum2 += err * err;
            acc.count += 1;
            second.0 += err * err;
            second.1 += 1;
        }
    }
    acc
}

fn satellite_stats(out: &ChainOutput, sc: &Scene, cn0: f64) -> Vec<SatStats> {
    out.tracked
        .iter()
        .map(|t| {
            let (best, first_lock) = lock_stretch(&t.epochs);
            let acc = settled(t, sc, cn0);
            SatStats {
                prn: t.acquisition.prn.number(),
                cn0_reports: t
                    .epochs
                    .iter()
                    .enumerate()
                    .filter(|(j, e)| e.t >= SETTLED_S && j % CN0_REPORT_EPOCHS == 0)
                    .map(|(_, e)| e.cn0_dbhz)
                    .collect(),
                lock_held_s: best,
                first_lock_s: first_lock,
                cn0_err_max: acc.cn0_err,
                cn0_mean: acc.cn0_sum / acc.cn0_n.max(1) as f64,
                phase_sum2: acc.sum2,
                phase_count: acc.count,
                per_second: acc.per_second,
            }
        })
        .collect()
}

fn write_files(
    dir: &std::path::Path,
    params: &ChainParams,
    out: &ChainOutput,
    o: &mut Outcome,
    cn0: f64,
) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let stats = satellite_stats(out, &params.scene, cn0);
    let csv = dir.join("signal_per_second.csv");
    write_csv(
        &csv,
        &[
            "t_s",
            "prn",
            "cn0_dbhz",
            "doppler_err_hz",
            "phase_diff_err_rms_cycles",
        ],
        stats.iter().flat_map(|s| s.per_second.iter().copied()),
    )?;
    o.files.push(csv);
    let png = dir.join("signal.png");
    let series = |col: usize| -> Vec<Series> {
        stats
            .iter()
            .enumerate()
            .map(|(c, s)| {
                Series::line(
                    format!("PRN {}", s.prn),
                    s.per_second.iter().map(|r| (r[0], r[col])).collect(),
                    c,
                )
            })
            .collect()
    };
    plot_panels(
        &png,
        &format!("signal: 8 satellites at {cn0} dB-Hz, three antennas, CS8 2.6 Msps"),
        "time (s)",
        &[
            Panel {
                y_label: "C/N0 estimate (dB-Hz)".into(),
                series: series(2),
            },
            Panel {
                y_label: "Doppler error (Hz)".into(),
                series: series(3),
            },
            Panel {
                y_label: "phase-difference error RMS per s (cycle)".into(),
                series: series(4),
            },
        ],
    )?;
    o.files.push(png);
    // The first 100 ms as CS8 files (one per antenna), written and read back.
    let n = 260_000;
    let analog = params.scene.synthesize(0, n);
    let streams = encode(SampleFormat::Cs8, &analog)?;
    let paths = write_streams(dir, "signal_first_100ms", SampleFormat::Cs8, &streams)?;
    anyhow::ensure!(
        read_streams(&paths)? == streams,
        "CS8 files do not read back"
    );
    o.files.extend(paths);
    Ok(())
}
