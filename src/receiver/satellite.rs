//! Per-satellite bookkeeping: the navigation aiding (line of sight), the single-difference
//! carrier-phase counters of antennas B and C against A, their window sums, the fixed
//! ambiguities, and the data-bit monitor.
//!
//! # Single differences
//!
//! With prompts in noise units and the line biases removed, `z_P z_A*` has the phase
//! `ψ_P − ψ_A = 2π μᵀ C_rb (r_P − r_A)/λ`: the single difference (SD) of baseline `A→P` in
//! cycles, range sense (paper 002's `Δr/λ`), free of the data bit and of the common carrier
//! phase. Every epoch its wrapped value updates a **counter** that keeps whole cycles:
//! `c_k = ĉ_k + wrap(φ_k − ĉ_k)` with the prediction `ĉ_k = c_{k−1} + ṙ T` from the last
//! window's rate (an epoch whose prompts are too weak, `|z|² < 4` on either antenna, keeps the
//! prediction). Over a window the products are summed (`Σ z_P z_A*`, whose argument is the
//! window's SD to the noise level `1/(2π√(q_T n))`) and the counter is fitted by a straight
//! line (its slope is the SD rate, i.e. the velocity difference along the line of sight).
//! The window's SD keeps the argument's fraction and takes the whole cycles from the
//! counter's mean.
//!
//! A fixed ambiguity `K` makes `c − K` the geometric SD `b_Pᵀ C_rbᵀ μ / λ`.

use nalgebra::{Complex, Vector3};

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
/// to count: (0.1 cycle)², about four times the per-epoch noise of a 38 dB-Hz single
/// difference.
const MAX_LINE_MS: f32 = 0.01;

/// Smallest `|z|²` (noise units) of both antennas for an epoch to update a counter.
const MIN_EPOCH_POWER: f32 = 4.0;

/// What one window gives for one satellite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WindowSd {
    pub prn: u8,
    /// Line of sight at the window's centre, reference frame.
    pub los: Vector3<f32>,
    /// Window SD of B and C: the counter's whole cycles with the products' fraction, cycles.
    pub phase: [f32; 2],
    /// SD rate of B and C (slope of the counter), cycles/s.
    pub rate: [f32; 2],
    /// Whether the SD of B / C is usable (coherent products, valid counter).
    pub valid: [bool; 2],
    /// Standard deviation of one window SD, cycles.
    pub sigma_cycles: f32,
}

/// Sums of one window.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
struct WindowSums {
    product: [Complex<f32>; 2],
    magnitude: [f32; 2],
    epochs: u32,
    /// Counter at the window's first epoch (the fit is done relative to it).
    origin: [f32; 2],
    /// Σ τ, Σ τ², Σ c', Σ τ c' with τ = epoch offset in the window (epochs), c' = c − origin.
    s_t: f32,
    s_tt: f32,
    s_c: [f32; 2],
    s_tc: [f32; 2],
    /// Σ c'² (for the residual of the straight line).
    s_cc: [f32; 2],
    cn0_linear: f32,
    counter_ok: [bool; 2],
}

/// Data-bit edge monitor on the reference antenna's prompt: learns where the sign of `I_A`
/// changes (every 20 ms at the bit edges) and flags a change elsewhere.
///
/// Only epochs with `|I_A| > 3σ` count. A sign change between two such epochs at most
/// [`BIT_GAP`] epochs apart happened somewhere between them: if none of those positions is the
/// learned edge (or its neighbours), it is an anomaly; a change between consecutive epochs at
/// the edge teaches the histogram.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BitMonitor {
    histogram: [f32; 20],
    last_i: f32,
    last_epoch: Option<u64>,
}

impl Default for BitMonitor {
    fn default() -> Self {
        Self {
            histogram: [0.0; 20],
            last_i: 0.0,
            last_epoch: None,
        }
    }
}

/// Smallest `|I_A|` (noise units) on both sides of a sign change for the monitor to count it.
const BIT_SIGN_LEVEL: f32 = 3.0;

/// Largest gap (epochs) between the two strong epochs of a sign change the monitor judges.
const BIT_GAP: u64 = 3;

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
                let (best, best_count, second) = self.peak();
                let learned = best_count >= 8.0 && best_count >= 4.0 * second;
                let near = |p: u64| {
                    let d = (p + 20 - best as u64) % 20;
                    d == 0 || d == 1 || d == 19
                };
                // the change happened at one of the epochs last + 1 ..= epoch
                let at_edge = (last + 1..=epoch).any(|e| near(e % 20));
                if learned && !at_edge {
                    anomaly = true;
                } else if gap == 1 {
                    // forget slowly: the edges drift against the receiver's epochs with Doppler
                    for h in self.histogram.iter_mut() {
                        *h *= 0.97;
                    }
                    if let Some(h) = self.histogram.get_mut((epoch % 20) as usize) {
                        *h += 1.0;
                    }
                }
            }
        }
        self.last_i = i_a;
        self.last_epoch = Some(epoch);
        anomaly
    }

    /// (position of the largest bin, its weight plus its neighbours', the largest weight
    /// elsewhere).
    fn peak(&self) -> (usize, f32, f32) {
        let w = |p: usize| self.histogram.get(p % 20).copied().unwrap_or(0.0);
        let mut best = 0usize;
        let mut best_w = -1.0f32;
        for p in 0..20 {
            let s = w(p + 19) + w(p) + w(p + 1);
            if s > best_w {
                best_w = s;
                best = p;
            }
        }
        let mut second = 0.0f32;
        for p in 0..20 {
            let d = (p + 20 - best) % 20;
            if d > 2 && d < 18 {
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
    /// SD counters of B and C, cycles (whole cycles kept).
    pub counter: [f32; 2],
    /// Whether each counter has been started (and not invalidated).
    pub counter_valid: [bool; 2],
    /// SD rate of the last window, cycles/s (the counters' prediction).
    pub rate: [f32; 2],
    /// Fixed ambiguities: `c − K` is the geometric SD.
    pub ambiguity: [Option<i32>; 2],
    /// The ambiguity a window dropped because its counter jumped (a cycle slip suspected):
    /// the re-fix is compared with it.
    pub dropped: [Option<i32>; 2],
    /// Latest C/N0, dB-Hz.
    pub cn0_dbhz: f32,
    window: WindowSums,
    bits: BitMonitor,
}

fn wrap_cycles(x: f32) -> f32 {
    x - libm::roundf(x)
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
            window: WindowSums::default(),
            bits: BitMonitor::default(),
        }
    }

    /// The line of sight at `epoch` (extrapolated from the aiding, renormalized).
    pub fn los_at(&self, epoch: u64, epoch_s: f32) -> Vector3<f32> {
        let dt = (epoch as f64 - self.aiding.epoch as f64) as f32 * epoch_s;
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
        if let Some(k) = p.checked_sub(1) {
            if let Some(v) = self.counter_valid.get_mut(k) {
                *v = false;
            }
            if let Some(a) = self.ambiguity.get_mut(k) {
                *a = None;
            }
            if let Some(d) = self.dropped.get_mut(k) {
                *d = None;
            }
        }
    }

    /// Adds one epoch: `z` are the prompts of A, B, C in noise units with the line biases
    /// removed, `blocked` the antennas left out. Returns true when the data-bit monitor saw a
    /// sign change away from the bit edges.
    pub fn add_epoch(
        &mut self,
        epoch: u64,
        z: &[Complex<f32>; 3],
        cn0_dbhz: f32,
        epoch_s: f32,
        window_epochs: u32,
        blocked: &[bool; 3],
    ) -> bool {
        let [za, zb, zc] = *z;
        let tau = epoch.checked_rem(u64::from(window_epochs)).unwrap_or(0) as f32;
        let w = &mut self.window;
        if w.epochs == 0 {
            *w = WindowSums::default();
        }
        let power_a = za.norm_sqr();
        for (k, zp) in [zb, zc].into_iter().enumerate() {
            let (Some(c), Some(valid), Some(rate)) = (
                self.counter.get_mut(k),
                self.counter_valid.get_mut(k),
                self.rate.get(k),
            ) else {
                continue;
            };
            let antenna_blocked = blocked.get(k + 1).copied().unwrap_or(true);
            let product = zp * za.conj();
            let strong = power_a >= MIN_EPOCH_POWER && zp.norm_sqr() >= MIN_EPOCH_POWER;
            let phase = libm::atan2f(product.im, product.re) * (0.5 * core::f32::consts::FRAC_1_PI);
            if antenna_blocked {
                *valid = false;
            } else if !*valid {
                if strong {
                    *c = phase;
                    *valid = true;
                }
            } else {
                // c_k = ĉ_k + wrap(φ_k − ĉ_k), ĉ_k = c_{k−1} + rate·T
                let predicted = *c + *rate * epoch_s;
                *c = if strong {
                    predicted + wrap_cycles(phase - predicted)
                } else {
                    predicted
                };
            }
            if let (Some(p), Some(m)) = (w.product.get_mut(k), w.magnitude.get_mut(k)) {
                *p += product;
                *m += libm::sqrtf(product.norm_sqr());
            }
            if w.epochs == 0 {
                if let (Some(o), Some(ok)) = (w.origin.get_mut(k), w.counter_ok.get_mut(k)) {
                    *o = *c;
                    *ok = *valid;
                }
            }
            let origin = w.origin.get(k).copied().unwrap_or(0.0);
            let rel = *c - origin;
            if let (Some(sc), Some(stc), Some(scc), Some(ok)) = (
                w.s_c.get_mut(k),
                w.s_tc.get_mut(k),
                w.s_cc.get_mut(k),
                w.counter_ok.get_mut(k),
            ) {
                *sc += rel;
                *stc += tau * rel;
                *scc += rel * rel;
                *ok &= *valid;
            }
        }
        w.s_t += tau;
        w.s_tt += tau * tau;
        w.cn0_linear += libm::powf(10.0, 0.1 * cn0_dbhz);
        w.epochs += 1;
        self.cn0_dbhz = cn0_dbhz;
        self.last_epoch = Some(epoch);
        self.bits.update(epoch, za.re)
    }

    /// Closes the window at `centre_epoch` and starts the next one; `None` when it had too
    /// few epochs (a quarter of the window).
    pub fn close_window(&mut self, centre_epoch: u64, config: &ReceiverConfig) -> Option<WindowSd> {
        let w = self.window;
        self.window = WindowSums::default();
        let n = w.epochs as f32;
        if w.epochs < (config.window_epochs / 4).max(4) {
            return None;
        }
        let t = config.epoch_s;
        let mut out = WindowSd {
            prn: self.aiding.prn,
            los: self.los_at(centre_epoch, t),
            phase: [0.0; 2],
            rate: [0.0; 2],
            valid: [false; 2],
            sigma_cycles: 0.0,
        };
        // slope of the counter: S_τc / S_ττ (centred sums)
        let s_tt = w.s_tt - w.s_t * w.s_t / n;
        let mean_tau = w.s_t / n;
        // the window's centre in τ: the centre epoch's offset
        let centre_tau = (config.window_epochs as f32 - 1.0) * 0.5;
        for k in 0..2 {
            let (Some(p), Some(m), Some(sc), Some(stc), Some(scc), Some(origin), Some(ok)) = (
                w.product.get(k),
                w.magnitude.get(k),
                w.s_c.get(k),
                w.s_tc.get(k),
                w.s_cc.get(k),
                w.origin.get(k),
                w.counter_ok.get(k),
            ) else {
                continue;
            };
            let s_tc = stc - w.s_t * sc / n;
            let slope_per_epoch = if s_tt > 0.0 { s_tc / s_tt } else { 0.0 };
            // mean square of the counter about its straight line: large when the counter ran
            // on noise for part of the window (a satellite setting, a fade), whose slope would
            // be garbage
            let s_cc = scc - sc * sc / n;
            let line_ms = ((s_cc - slope_per_epoch * s_tc) / n).max(0.0);
            let straight = line_ms <= MAX_LINE_MS;
            let mean_c = origin + sc / n + slope_per_epoch * (centre_tau - mean_tau);
            let fraction = libm::atan2f(p.im, p.re) * (0.5 * core::f32::consts::FRAC_1_PI);
            let phase = fraction + libm::roundf(mean_c - fraction);
            // coherence: |Σ z z*| / Σ |z z*| is near 1 for a clean SD, near 1/√n for noise
            let coherent = *m > 0.0 && libm::sqrtf(p.norm_sqr()) >= 0.5 * m;
            let valid =
                *ok && coherent && straight && self.counter_valid.get(k).copied().unwrap_or(false);
            let rate = slope_per_epoch / t;
            if let (Some(ph), Some(r), Some(v), Some(sr)) = (
                out.phase.get_mut(k),
                out.rate.get_mut(k),
                out.valid.get_mut(k),
                self.rate.get_mut(k),
            ) {
                *ph = phase;
                *r = rate;
                *v = valid;
                if valid && rate.is_finite() {
                    *sr = rate;
                }
            }
            if !valid {
                // the counter can no longer be trusted to hold whole cycles; if it kept running
                // on a coherent signal and only jumped, remember the integer (a slip suspected)
                let running =
                    *ok && coherent && self.counter_valid.get(k).copied().unwrap_or(false);
                if let (Some(a), Some(d)) = (self.ambiguity.get_mut(k), self.dropped.get_mut(k)) {
                    *d = if running { a.or(*d) } else { None };
                    *a = None;
                }
            }
        }
        // σ = 1/(2π √(q_T n)), q_T n = Σ (C/N0) T
        let qn = w.cn0_linear * t;
        out.sigma_cycles = if qn > 0.0 {
            0.5 * core::f32::consts::FRAC_1_PI / libm::sqrtf(qn)
        } else {
            0.5
        };
        Some(out)
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
}
