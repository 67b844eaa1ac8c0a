//! Per-satellite bookkeeping: the navigation aiding (line of sight), the single differences of
//! antennas B and C against A summed over blocks and windows, the counters that keep their
//! whole cycles, the fixed ambiguities, and the data-bit monitor.
//!
//! # Single differences
//!
//! With prompts in noise units, `z_P z_A*` has the phase
//! `ψ_P − ψ_A + β_P = 2π μᵀ C_rb (r_P − r_A)/λ + β_P`: the single difference (SD) of baseline
//! `A→P` plus the line bias `β_P` of P's RF chain, free of the data bit and of the common
//! carrier phase. Every epoch the products and the antennas' powers are summed into the
//! **block** (a few tens of milliseconds, [`ReceiverConfig::block_epochs`]); a block gives the
//! fine filter one phase per baseline, `arg Σ z_P z_A*`, with its covariance
//!
//! ```text
//! Var φ_P = (q_A + q_P + 1) / (2 n q_A q_P),   Cov(φ_B, φ_C) = 1 / (2 n q_A)
//! ```
//!
//! (`q_P` the per-epoch signal-to-noise ratio of antenna P measured from the block's own powers,
//! `|z_P|² = 2 q_P + 2`, smoothed over blocks; `n` epochs; the two share A's noise). Each
//! block's phase, in cycles, updates a **counter** that keeps whole cycles,
//! `c = ĉ + wrap(φ − ĉ)` with the prediction `ĉ = c + ṙ τ` from the last window's rate; over a
//! **window** the counter is fitted by a straight line (its slope is the SD rate, the velocity
//! difference along the line of sight) and the products are summed again: the window's SD
//! keeps the summed products' fraction and takes the whole cycles from the counter's mean.
//! A fixed ambiguity `K` makes `c − K − β_P/2π` the geometric SD `b_Pᵀ C_rbᵀ μ / λ`.

use nalgebra::{Complex, Matrix2, Vector2, Vector3};

use super::config::ReceiverConfig;

/// Navigation aiding for one satellite: its line of sight (from the onboard navigation
/// solution and the ephemeris; host-sim takes it from its truth and the almanac).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SatelliteAiding {
    /// PRN.
    pub prn: u8,
    /// Epoch at which `los` holds.
    pub epoch: u64,
    /// Unit line of sight from the spacecraft to the satellite, reference frame (the frame
    /// the attitude is reported in: ECI in host-sim).
    pub los: [f32; 3],
    /// Its time derivative, 1/s (extrapolates the line of sight between aiding updates).
    pub los_rate: [f32; 3],
}

/// Largest mean square (cycles²) of a window's counter about its straight line for the window
/// to count: (0.1 cycle)².
const MAX_LINE_MS: f32 = 0.01;

/// Smallest smoothed per-epoch SNR `q` of both antennas for a block to count (q = 1 is
/// 30 dB-Hz at 1 ms).
const MIN_BLOCK_SNR: f32 = 1.0;

/// Floor of a measured per-epoch SNR (a block of noise gives about zero).
const SNR_FLOOR: f32 = 1e-3;

/// Smoothing gain of the per-antenna SNR over blocks.
const SNR_GAIN: f32 = 0.2;

/// Smallest `|Σ z z*| / Σ |z z*|` of a block or window for its phase to count: near 1 for a
/// clean SD, `1/√n` for noise.
const MIN_COHERENCE: f32 = 0.5;

/// One block's single differences of one satellite, for the fine filter and the counters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BlockSd {
    pub prn: u8,
    /// Line of sight at the block's centre, reference frame.
    pub los: Vector3<f32>,
    /// `arg Σ z_P z_A*` of B and C, rad (line biases included).
    pub phase_rad: Vector2<f32>,
    /// Their covariance, rad².
    pub covariance: Matrix2<f32>,
    /// Whether both are usable (enough epochs, signal on the three antennas, coherent).
    pub valid: bool,
}

/// What one window gives for one satellite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WindowSd {
    pub prn: u8,
    /// Line of sight at the window's centre, reference frame.
    pub los: Vector3<f32>,
    /// Window SD of B and C (line biases included): the counter's whole cycles with the
    /// products' fraction, cycles.
    pub phase: [f32; 2],
    /// SD rate of B and C (slope of the counter), cycles/s.
    pub rate: [f32; 2],
    /// Whether the SD of B / C is usable (coherent products, valid counter).
    pub valid: [bool; 2],
    /// Standard deviation of one window SD, cycles.
    pub sigma_cycles: f32,
}

/// Sums of one block.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
struct BlockSums {
    product: [Complex<f32>; 2],
    magnitude: [f32; 2],
    power: [f32; 3],
    epochs: u32,
}

/// Sums of one window, over its blocks.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
struct WindowSums {
    product: [Complex<f32>; 2],
    magnitude: [f32; 2],
    blocks: u32,
    /// Counter at the window's first block (the fit is done relative to it).
    origin: [f32; 2],
    /// Σ τ, Σ τ², Σ c', Σ τ c', Σ c'² with τ the block's centre (epochs into the window) and
    /// c' = c − origin.
    s_t: f32,
    s_tt: f32,
    s_c: [f32; 2],
    s_tc: [f32; 2],
    s_cc: [f32; 2],
    /// Σ n / Var₁ over the blocks: the information of the window's SD, 1/rad² (`Var₁` the
    /// one-epoch SD variance of the weaker baseline).
    information: f32,
    counter_ok: [bool; 2],
}

/// Data-bit edge monitor on the reference antenna's prompt: learns where the sign of `I_A`
/// changes (every 20 ms at the bit edges) and flags a change elsewhere.
///
/// Only epochs with `|I_A| >` [`BIT_SIGN_LEVEL`] count. A sign change between two such epochs
/// at most [`BIT_GAP`] epochs apart happened somewhere between them: if none of those
/// positions is the learned edge (or its neighbours), it is an anomaly; a change between
/// consecutive epochs at the edge teaches the histogram.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BitMonitor {
    histogram: [f32; BIT_EPOCHS],
    last_i: f32,
    last_epoch: Option<u64>,
}

/// Epochs per data bit (GPS L1 C/A: 20 code periods).
const BIT_EPOCHS: usize = 20;

/// Smallest `|I_A|` (noise units) on both sides of a sign change for the monitor to count it.
const BIT_SIGN_LEVEL: f32 = 3.0;

/// Largest gap (epochs) between the two strong epochs of a sign change the monitor judges.
const BIT_GAP: u64 = 3;

/// Weight (plus neighbours) the learned edge needs, and its margin over any other bin.
const BIT_LEARNED_WEIGHT: f32 = 8.0;
const BIT_LEARNED_MARGIN: f32 = 4.0;

/// Weight an anomalous transition adds at its position: a moved edge is learned after
/// about `BIT_LEARNED_WEIGHT / BIT_RELEARN_WEIGHT` bits.
const BIT_RELEARN_WEIGHT: f32 = 0.25;

/// Forgetting of the histogram per learned edge (the edges drift against the receiver's
/// epochs with the Doppler).
const BIT_FORGET: f32 = 0.97;

impl Default for BitMonitor {
    fn default() -> Self {
        Self {
            histogram: [0.0; BIT_EPOCHS],
            last_i: 0.0,
            last_epoch: None,
        }
    }
}

impl BitMonitor {
    /// Takes the reference prompt's I (noise units) of `epoch`; true when the sign changed at a
    /// position that is not the learned bit edge.
    fn update(&mut self, epoch: u64, i_a: f32) -> bool {
        if !(i_a.abs() > BIT_SIGN_LEVEL) {
            return false;
        }
        let mut anomaly = false;
        if let Some(last) = self.last_epoch {
            let gap = epoch.saturating_sub(last);
            if (1..=BIT_GAP).contains(&gap) && (self.last_i > 0.0) != (i_a > 0.0) {
                anomaly = self.judge_change(last, epoch, gap);
            }
        }
        self.last_i = i_a;
        self.last_epoch = Some(epoch);
        anomaly
    }

    /// A sign change somewhere in `last + 1 ..= epoch`: an anomaly once the edge is learned
    /// and none of those positions is near it; else (consecutive epochs) a lesson.
    fn judge_change(&mut self, last: u64, epoch: u64, gap: u64) -> bool {
        let (best, best_weight, second) = self.peak();
        let learned =
            best_weight >= BIT_LEARNED_WEIGHT && best_weight >= BIT_LEARNED_MARGIN * second;
        let period = BIT_EPOCHS as u64;
        let near = |e: u64| {
            let d = (e % period + period - best as u64 % period) % period;
            d == 0 || d == 1 || d == period - 1
        };
        let at_edge = (last.saturating_add(1)..=epoch).any(near);
        if learned && !at_edge {
            // an edge that moved (a re-acquired channel, the code's drift against the epochs)
            // takes over after a few dozen bits; a single wrong transition does not
            if gap == 1 {
                self.histogram[(epoch % period) as usize] += BIT_RELEARN_WEIGHT;
            }
            return true;
        }
        if gap == 1 {
            for h in self.histogram.iter_mut() {
                *h *= BIT_FORGET;
            }
            self.histogram[(epoch % period) as usize] += 1.0;
        }
        false
    }

    /// (position of the largest bin, its weight plus its neighbours', the largest weight
    /// elsewhere).
    fn peak(&self) -> (usize, f32, f32) {
        let w = |p: usize| self.histogram[p % BIT_EPOCHS];
        let mut best = 0usize;
        let mut best_w = -1.0f32;
        for p in 0..BIT_EPOCHS {
            let s = w(p + BIT_EPOCHS - 1) + w(p) + w(p + 1);
            if s > best_w {
                best_w = s;
                best = p;
            }
        }
        let mut second = 0.0f32;
        for p in 0..BIT_EPOCHS {
            let d = (p + BIT_EPOCHS - best) % BIT_EPOCHS;
            if d > 2 && d < BIT_EPOCHS - 2 {
                second = second.max(w(p));
            }
        }
        (best, best_w, second)
    }
}

/// One satellite's slot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Slot {
    pub aiding: SatelliteAiding,
    /// Last epoch with an observation.
    pub last_epoch: Option<u64>,
    /// SD counters of B and C, cycles (whole cycles kept, line biases included).
    counter: [f32; 2],
    /// Whether each counter has been started (and not invalidated).
    counter_valid: [bool; 2],
    /// SD rate of the last window, cycles/s (the counters' prediction).
    rate: [f32; 2],
    /// Fixed ambiguities: `c − K − β/2π` is the geometric SD.
    pub ambiguity: [Option<i32>; 2],
    /// The ambiguity a window dropped because its counter jumped (a cycle slip suspected):
    /// the re-fix is compared with it.
    pub dropped: [Option<i32>; 2],
    /// Latest C/N0, dB-Hz.
    pub cn0_dbhz: f32,
    /// Smoothed per-epoch SNR of A, B, C (0 before the first block).
    snr: [f32; 3],
    block: BlockSums,
    window: WindowSums,
    bits: BitMonitor,
}

fn wrap_cycles(x: f32) -> f32 {
    x - libm::roundf(x)
}

/// `atan2` of a complex number, in cycles.
fn arg_cycles(z: Complex<f32>) -> f32 {
    libm::atan2f(z.im, z.re) * (0.5 * core::f32::consts::FRAC_1_PI)
}

/// Epochs of `epoch` into its window.
fn window_offset(epoch: u64, config: &ReceiverConfig) -> f32 {
    epoch
        .checked_rem(u64::from(config.window_epochs))
        .unwrap_or(0) as f32
}

/// `(q_A + q_P + 1) / (2 q_A q_P)`: the variance (rad²) of one epoch's SD phase.
fn sd_variance_per_epoch(q_a: f32, q_p: f32) -> f32 {
    (q_a + q_p + 1.0) / (2.0 * q_a * q_p)
}

impl Slot {
    pub fn new(aiding: SatelliteAiding) -> Self {
        Self {
            aiding,
            last_epoch: None,
            counter: [0.0; 2],
            counter_valid: [false; 2],
            rate: [0.0; 2],
            ambiguity: [None; 2],
            dropped: [None; 2],
            cn0_dbhz: 0.0,
            snr: [0.0; 3],
            block: BlockSums::default(),
            window: WindowSums::default(),
            bits: BitMonitor::default(),
        }
    }

    /// The slot started afresh for the same aiding (a satellite lost and found again).
    pub fn restarted(&self) -> Self {
        Self::new(self.aiding)
    }

    /// Forgets every integer (a cold start follows).
    pub fn forget_ambiguities(&mut self) {
        self.ambiguity = [None; 2];
        self.dropped = [None; 2];
    }

    /// Whether both baselines' integers are fixed.
    pub fn fixed(&self) -> bool {
        self.ambiguity.iter().all(Option::is_some)
    }

    /// The line of sight at `epoch` (extrapolated from the aiding, renormalized).
    pub fn los_at(&self, epoch: u64, epoch_s: f32) -> Vector3<f32> {
        // (two's complement: the signed epoch difference without a soft-float conversion)
        let dt = epoch.wrapping_sub(self.aiding.epoch) as i64 as f32 * epoch_s;
        let v = Vector3::from(self.aiding.los) + Vector3::from(self.aiding.los_rate) * dt;
        let n = v.norm();
        if n > 0.5 {
            v / n
        } else {
            Vector3::from(self.aiding.los)
        }
    }

    /// Invalidates the counter (and ambiguity) of antenna `p` (1 = B, 2 = C).
    pub fn invalidate(&mut self, p: usize) {
        if let Some(k) = p.checked_sub(1).filter(|&k| k < 2) {
            self.counter_valid[k] = false;
            self.ambiguity[k] = None;
            self.dropped[k] = None;
        }
    }

    /// Adds one epoch: `z` are the prompts of A, B, C in noise units. Returns true when the
    /// data-bit monitor saw a sign change away from the bit edges.
    pub fn add_epoch(&mut self, epoch: u64, z: &[Complex<f32>; 3], cn0_dbhz: f32) -> bool {
        let [za, zb, zc] = *z;
        let b = &mut self.block;
        for (k, zp) in (0..2).zip([zb, zc]) {
            let product = zp * za.conj();
            b.product[k] += product;
            b.magnitude[k] += crate::sqrtf(product.norm_sqr());
        }
        for (p, zp) in b.power.iter_mut().zip(z.iter()) {
            *p += zp.norm_sqr();
        }
        b.epochs = b.epochs.saturating_add(1); // (a block's epochs: far below u32::MAX)
        self.cn0_dbhz = cn0_dbhz;
        self.last_epoch = Some(epoch);
        self.bits.update(epoch, za.re)
    }

    /// Closes the block centred on `centre_epoch` (`min_epochs` needed) with the antennas in
    /// `blocked` left out: its single differences, and the counters and window sums advanced.
    pub fn close_block(
        &mut self,
        centre_epoch: u64,
        min_epochs: u32,
        blocked: &[bool; 3],
        config: &ReceiverConfig,
    ) -> Option<BlockSd> {
        let b = core::mem::take(&mut self.block);
        if b.epochs == 0 {
            return None;
        }
        let n = b.epochs as f32;
        for (s, p) in self.snr.iter_mut().zip(b.power.iter()) {
            let q = (0.5 * p / n - 1.0).max(SNR_FLOOR);
            *s = if *s > 0.0 {
                *s + SNR_GAIN * (q - *s)
            } else {
                q
            };
        }
        let [qa, qb, qc] = self.snr;
        let coherent = |k: usize| {
            b.magnitude[k] > 0.0
                && crate::sqrtf(b.product[k].norm_sqr()) >= MIN_COHERENCE * b.magnitude[k]
        };
        let strong = |q: f32, k: usize| q >= MIN_BLOCK_SNR && !blocked[k];
        let usable = [
            strong(qa, 0) && strong(qb, 1) && coherent(0),
            strong(qa, 0) && strong(qc, 2) && coherent(1),
        ];
        let valid = b.epochs >= min_epochs && usable == [true, true];
        let phase = Vector2::new(arg_cycles(b.product[0]), arg_cycles(b.product[1]));
        self.advance_counters(centre_epoch, &phase, &usable, blocked, config);
        let (vb, vc) = (
            sd_variance_per_epoch(qa, qb) / n,
            sd_variance_per_epoch(qa, qc) / n,
        );
        let cov_bc = 1.0 / (2.0 * n * qa);
        self.window.information += n / sd_variance_per_epoch(qa, qb.min(qc));
        for k in 0..2 {
            self.window.product[k] += b.product[k];
            self.window.magnitude[k] += b.magnitude[k];
        }
        Some(BlockSd {
            prn: self.aiding.prn,
            los: self.los_at(centre_epoch, config.epoch_s),
            phase_rad: phase * core::f32::consts::TAU,
            covariance: Matrix2::new(vb, cov_bc, cov_bc, vc),
            valid,
        })
    }

    /// The counters of a block (its phases in cycles) and the window's fit sums.
    fn advance_counters(
        &mut self,
        centre_epoch: u64,
        phase: &Vector2<f32>,
        usable: &[bool; 2],
        blocked: &[bool; 3],
        config: &ReceiverConfig,
    ) {
        let block_s = config.block_epochs as f32 * config.epoch_s;
        let tau = window_offset(centre_epoch, config);
        let w = &mut self.window;
        let first = w.blocks == 0;
        for k in 0..2 {
            let c = &mut self.counter[k];
            let valid = &mut self.counter_valid[k];
            if blocked[k + 1] {
                *valid = false;
            } else if !*valid {
                if usable[k] {
                    *c = phase[k];
                    *valid = true;
                }
            } else {
                // c = ĉ + wrap(φ − ĉ), ĉ = c + rate·τ_block
                let predicted = *c + self.rate[k] * block_s;
                *c = if usable[k] {
                    predicted + wrap_cycles(phase[k] - predicted)
                } else {
                    predicted
                };
            }
            if first {
                w.origin[k] = *c;
                w.counter_ok[k] = *valid;
            }
            let rel = *c - w.origin[k];
            w.s_c[k] += rel;
            w.s_tc[k] += tau * rel;
            w.s_cc[k] += rel * rel;
            w.counter_ok[k] &= *valid && usable[k];
        }
        w.s_t += tau;
        w.s_tt += tau * tau;
        w.blocks = w.blocks.saturating_add(1); // (a window's blocks: far below u32::MAX)
    }

    /// Closes the window at `centre_epoch` and starts the next one; `None` when it had too
    /// few blocks (half the window's).
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn close_window(&mut self, centre_epoch: u64, config: &ReceiverConfig) -> Option<WindowSd> {
        let w = core::mem::take(&mut self.window);
        let blocks_per_window = config.window_epochs / config.block_epochs.max(1);
        if w.blocks < (blocks_per_window / 2).max(2) {
            return None;
        }
        let n = w.blocks as f32;
        let t = config.epoch_s;
        let mut out = WindowSd {
            prn: self.aiding.prn,
            los: self.los_at(centre_epoch, t),
            phase: [0.0; 2],
            rate: [0.0; 2],
            valid: [false; 2],
            sigma_cycles: 0.5,
        };
        // slope of the counter: S_τc / S_ττ (centred sums), τ in epochs
        let s_tt = w.s_tt - w.s_t * w.s_t / n;
        let mean_tau = w.s_t / n;
        let centre_tau = window_offset(centre_epoch, config);
        for k in 0..2 {
            let s_tc = w.s_tc[k] - w.s_t * w.s_c[k] / n;
            let slope_per_epoch = if s_tt > 0.0 { s_tc / s_tt } else { 0.0 };
            // mean square of the counter about its straight line: large when the counter ran
            // on noise for part of the window (a satellite setting, a fade)
            let s_cc = w.s_cc[k] - w.s_c[k] * w.s_c[k] / n;
            let line_ms = ((s_cc - slope_per_epoch * s_tc) / n).max(0.0);
            let straight = line_ms <= MAX_LINE_MS;
            let mean_c = w.origin[k] + w.s_c[k] / n + slope_per_epoch * (centre_tau - mean_tau);
            let fraction = arg_cycles(w.product[k]);
            let coherent = w.magnitude[k] > 0.0
                && crate::sqrtf(w.product[k].norm_sqr()) >= MIN_COHERENCE * w.magnitude[k];
            let valid = w.counter_ok[k] && coherent && straight && self.counter_valid[k];
            let rate = slope_per_epoch / t;
            out.phase[k] = fraction + libm::roundf(mean_c - fraction);
            out.rate[k] = rate;
            out.valid[k] = valid;
            if valid && rate.is_finite() {
                self.rate[k] = rate;
            } else {
                // (every block usable: the counter ran on the signal; the window's own coherence
                // says nothing when the phase moved, as in a slip)
                self.drop_ambiguity(k, w.counter_ok[k]);
            }
        }
        // σ (cycles) = 1/(2π √information)
        if w.information > 0.0 {
            out.sigma_cycles = 0.5 * core::f32::consts::FRAC_1_PI / crate::sqrtf(w.information);
        }
        Some(out)
    }

    /// The counter can no longer be trusted to hold whole cycles; if it kept running on
    /// usable blocks and only jumped, the integer is remembered (a slip suspected).
    fn drop_ambiguity(&mut self, k: usize, running: bool) {
        let running = running && self.counter_valid[k];
        self.dropped[k] = if running {
            self.ambiguity[k].or(self.dropped[k])
        } else {
            None
        };
        self.ambiguity[k] = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bit_monitor_learns_the_edges_and_flags_a_change_elsewhere() {
        let mut m = BitMonitor::default();
        let mut sign = 1.0;
        let mut flagged = 0;
        for k in 0..2000u64 {
            if k % 20 == 7 && (k / 20) % 2 == 0 {
                sign = -sign;
            }
            if m.update(k, 8.0 * sign) {
                flagged += 1;
            }
        }
        assert_eq!(flagged, 0);
        // a flip 9 epochs after an edge
        assert!(!m.update(2000, 8.0 * sign));
        assert!(m.update(2001, -8.0 * sign));
    }

    #[test]
    fn the_block_covariance_matches_the_scatter_of_noisy_products() {
        // q = 10 (40 dB-Hz at 1 ms) on every antenna, 20 epochs per block
        use crate::noise::{SplitMix64, StandardNormal};
        let mut rng = SplitMix64::new(3);
        let mut normal = StandardNormal::default();
        let config = ReceiverConfig::gps_l1(crate::receiver::example::antennas(), None);
        let aiding = SatelliteAiding {
            prn: 1,
            epoch: 0,
            los: [0.0, 0.0, 1.0],
            los_rate: [0.0; 3],
        };
        let a = crate::sqrtf(2.0 * 10.0);
        let (mut sum, mut sum2, mut predicted) = (Vector2::zeros(), Vector2::zeros(), 0.0);
        let mut cross = 0.0;
        let runs = 400;
        let mut slot = Slot::new(aiding);
        for r in 0..runs {
            for e in 0..20u64 {
                let mut noise = || Complex::new(normal.sample(&mut rng), normal.sample(&mut rng));
                let z = [
                    Complex::new(a, 0.0) + noise(),
                    Complex::new(a * 0.6, a * 0.8) + noise(),
                    Complex::new(0.0, a) + noise(),
                ];
                slot.add_epoch(r * 20 + e, &z, 40.0);
            }
            let b = slot
                .close_block(r * 20 + 10, 10, &[false; 3], &config)
                .expect("block");
            let d = Vector2::new(
                b.phase_rad.x - 0.8f32.atan2(0.6),
                b.phase_rad.y - core::f32::consts::FRAC_PI_2,
            );
            sum += d;
            sum2 += d.component_mul(&d);
            cross += d.x * d.y;
            predicted = b.covariance[(0, 0)];
        }
        let n = runs as f32;
        let var = sum2 / n - (sum / n).component_mul(&(sum / n));
        // about 13 % sampling error of a variance from 400 draws
        assert!(
            (var.x / predicted - 1.0).abs() < 0.2,
            "{} vs {predicted}",
            var.x
        );
        assert!(
            (var.y / predicted - 1.0).abs() < 0.2,
            "{} vs {predicted}",
            var.y
        );
        // the shared antenna A: correlation 1/(2 + 2/q) ≈ 0.45
        let rho = (cross / n) / var.x;
        assert!((rho - 0.45).abs() < 0.15, "correlation {rho}");
    }
}
