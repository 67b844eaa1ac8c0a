//! The I/Q-level fast path: what the tracking channels hand over, synthesized directly with the
//! statistics of the sample-level chain, one 1 ms epoch at a time.
//!
//! For satellite `i` and antenna `P` the prompt is
//! `Z_P = A_P d e^{j(φ + ψ_P − ψ_A + b_P − b_A + s_P)} + n`, with `A_P = √(2 q_T) σ` (`q_T = (C/N0)_P T`, zero
//! where the antenna does not see the satellite), `d` the data bit, `φ` the reference loop's
//! phase error (the loop tracks antenna A's carrier, so A's prompt sits on I) (white, `σ_φ² = B_L/(C/N0)`, a 15 Hz PLL), `ψ_P` the geometric phase of eq. (4),
//! `b_P` the line bias, `s_P` an injected phase transient, and `n` complex Gaussian with `σ`
//! per component. This is what the crate's correlator returns once its loops track (the
//! `signal` scenario measures the chain's inter-antenna phase noise within 2–8 % of this
//! model's).
//!
//! The receiver measures the noise and C/N0 itself: each epoch also yields a noise tap per
//! antenna (`σ` per component) for the core's noise floor, and the channel's C/N0 comes from the
//! core's estimator on the reference prompt and noise tap (0.1 s, then 1 s windows).
//!
//! The channel's life is the receiver's decision, not the truth's. A channel starts only where
//! the core's acquisition detected its PRN in a synthesized search block
//! ([`super::fast_search`]: the receiver's own search list, retried after a failure as the
//! sample-level stretch does); it delivers epochs once the chain's refinement and pull-in
//! (256 ms + 300 ms) are over *and* the core's [`LockDetector`] (the tracking channel's
//! thresholds: C/N0 ≥ 26 dB-Hz, phase-lock indicator ≥ 0.5, a correlation peak, declared after
//! two good 100 ms windows) holds code and phase lock on the reference antenna's early,
//! prompt, late and noise taps (early and late at half the prompt's amplitude, the ½-chip
//! triangle; their noise drawn independently, which the window means do not see). Where the
//! satellite vanishes (below the reference antenna's mask, occulted, blocked) the taps carry
//! noise only: the channel keeps delivering those noise prompts until the detector's three bad
//! windows declare the lock lost, then stops, and is closed [`DROP_AFTER_S`] after its last
//! lock, as the core's `SampleReceiver` closes its channels; its PRN is searched again.
//!
//! # Cycle slips
//! The fault injected as a cycle slip turns a slaved antenna's phase by a whole cycle over
//! [`super::sample_level::SLIP_DURATION_S`] (100 ms). A one-cycle turn in 4 ms, the classic PLL
//! slip, is no fault of this receiver: it counts the single differences' whole cycles once per
//! 20 ms block from the block's phase, the four turning epochs' products sum to about zero, and
//! the count, the integers and the attitude stay as they were (consistent with the geometry:
//! a run with it reports the attitude inside 3σ and nothing detectable). The slow turn is the
//! one the counter counts while the geometry does not move, as a PLL slip does to a per-antenna
//! receiver's count; the ambiguity upkeep must find and repair it.

use gnss_attitude::attitude::one_stage::{PromptIq, SatelliteObservation};
use gnss_attitude::signal::correlator::{Iq, Taps};
use gnss_attitude::tracking::cn0::{PowerWindow, WindowEstimate};
use gnss_attitude::tracking::lock::{LockDetector, LockThresholds};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::sample_level::{SampleLevel, DROP_AFTER_S};
use super::world::SatTruth;

/// Noise standard deviation of each correlator component, counts (an arbitrary scale the
/// receiver normalizes away).
pub const NOISE_SIGMA: f64 = 40.0;
/// Epoch (code period), s.
pub const EPOCH_S: f64 = 1e-3;
/// Refinement and pull-in of the chain after a hand-over, s.
pub const PULL_IN_S: f64 = 0.556;
/// Early and late taps' amplitude over the prompt's (the ½-chip early/late offset on the
/// correlation triangle).
const EARLY_LATE_AMPLITUDE: f64 = 0.5;
/// PLL noise bandwidth of the reference loop, Hz.
pub const PLL_BANDWIDTH_HZ: f64 = 15.0;

/// Where an emulated channel is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChannelState {
    /// No channel.
    Idle,
    /// Detected; refining and pulling in until `ready_at` (s), delivering nothing.
    Acquiring {
        /// End of the refinement and pull-in, s.
        ready_at: f64,
    },
    /// Tracking: delivers while the lock detector holds code and phase lock.
    Tracking,
    /// The lock detector lost the code lock: delivers nothing until closed.
    Lost,
}

/// What happened to a channel in an epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChannelChange {
    /// Nothing.
    None,
    /// The lock detector declared the lock lost; `gone_s`: how long before the reference
    /// antenna had stopped receiving the satellite (world truth, for the metrics only).
    Lost {
        /// Seconds since the signal vanished (`None`: it had not).
        gone_s: Option<f64>,
    },
    /// Closed ([`DROP_AFTER_S`] without lock).
    Closed,
}

/// An injected phase transient: antenna `antenna`'s phase of this satellite turns by
/// `cycles` whole cycles over `duration_s` from `start_s`.
#[derive(Clone, Copy, Debug)]
pub struct PhaseTransient {
    /// Antenna (1 = B, 2 = C).
    pub antenna: usize,
    /// Start, s.
    pub start_s: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Cycles turned.
    pub cycles: f64,
}

/// One emulated channel.
#[derive(Clone, Debug)]
pub struct EmulatedChannel {
    /// PRN.
    pub prn: u8,
    /// State.
    pub state: ChannelState,
    bit: f64,
    bit_offset: u64,
    /// Data-sign inversion from `(time)` on: a bit transition at a time that is not an edge.
    pub bit_flip_at: Option<f64>,
    /// Phase transients on this satellite.
    pub transients: Vec<PhaseTransient>,
    cn0_estimate: f64,
    cn0_updated: f64,
    /// The core's C/N0 statistics of the reference antenna's prompt and noise taps.
    cn0_window: PowerWindow,
    flipped: bool,
    /// The core's lock detector, with the tracking channel's thresholds.
    lock: LockDetector,
    /// Its 100 ms window of the reference antenna's taps.
    lock_window: PowerWindow,
    /// Epochs per lock window.
    lock_epochs: u32,
    /// Last time with code and phase lock (the start before one), s.
    last_lock_s: f64,
    /// Since when the reference antenna has not received the satellite (world truth, for the
    /// metrics only), s.
    gone_since: Option<f64>,
    /// The early and late taps' noise (a stream of its own: the prompts' stream is the one the
    /// fast path always drew).
    tap_rng: ChaCha8Rng,
}

/// Seed salt of the early and late taps' noise.
const TAP_SEED_SALT: u64 = 0x7461_7073;
/// The first C/N0 window after a start, s (then [`CN0_WINDOW_S`]).
const CN0_FIRST_WINDOW_S: f64 = 0.1;
/// The C/N0 window, s.
const CN0_WINDOW_S: f64 = 1.0;

/// One complex Gaussian correlator output of `σ` per component, rounded to counts.
fn noise_iq(rng: &mut ChaCha8Rng, sigma: f64) -> Iq {
    let (i, q): (f64, f64) = (StandardNormal.sample(rng), StandardNormal.sample(rng));
    Iq {
        i: (sigma * i).round() as i32,
        q: (sigma * q).round() as i32,
    }
}

/// The lock thresholds and window of the core's tracking channel as the flight runs it.
fn lock_config() -> (LockThresholds, u32) {
    let c = SampleLevel::front_config().channel;
    (
        LockThresholds {
            cn0_dbhz: c.cn0_lock_threshold_dbhz,
            pld: c.pld_threshold,
            max_shape: c.max_correlation_shape,
            windows_to_declare: c.lock_windows_to_declare,
            windows_to_lose: c.lock_windows_to_lose,
        },
        u32::from(c.lock_window),
    )
}

impl EmulatedChannel {
    /// An idle channel.
    pub fn new(prn: u8, rng: &mut ChaCha8Rng) -> Self {
        let (thresholds, lock_epochs) = lock_config();
        Self {
            prn,
            state: ChannelState::Idle,
            bit: if rng.random_bool(0.5) { 1.0 } else { -1.0 },
            bit_offset: rng.random_range(0..20),
            bit_flip_at: None,
            transients: Vec::new(),
            cn0_estimate: 0.0,
            cn0_updated: f64::NEG_INFINITY,
            cn0_window: PowerWindow::default(),
            flipped: false,
            lock: LockDetector::new(&thresholds),
            lock_window: PowerWindow::default(),
            lock_epochs,
            last_lock_s: f64::NEG_INFINITY,
            gone_since: None,
            tap_rng: ChaCha8Rng::seed_from_u64(TAP_SEED_SALT ^ u64::from(prn)),
        }
    }

    /// Starts the channel on a detection at `t` (s): refinement and pull-in, lock detector and
    /// C/N0 afresh.
    pub fn start(&mut self, t: f64) {
        self.state = ChannelState::Acquiring {
            ready_at: t + PULL_IN_S,
        };
        self.lock.reset();
        self.lock_window = PowerWindow::default();
        self.cn0_window = PowerWindow::default();
        self.cn0_estimate = 0.0;
        self.cn0_updated = f64::NEG_INFINITY;
        self.last_lock_s = t;
        self.gone_since = None;
    }

    /// Continues a channel of the sample-level chain handed over locked at `t` (s) with C/N0
    /// `cn0_dbhz`: tracking, its lock detector carrying the chain's lock on (the good windows
    /// it declared the lock with).
    pub fn continue_tracking(&mut self, t: f64, cn0_dbhz: f64) {
        self.state = ChannelState::Tracking;
        self.lock.reset();
        let good = WindowEstimate {
            cn0_dbhz: cn0_dbhz as f32,
            phase_lock_indicator: 1.0,
            shape: 0.25,
            epochs: self.lock_epochs,
            ..WindowEstimate::default()
        };
        for _ in 0..self.lock.windows_to_declare {
            self.lock.update(&good);
        }
        self.last_lock_s = t;
        self.gone_since = None;
    }

    /// Whether the channel runs (searched and not closed).
    pub fn active(&self) -> bool {
        self.state != ChannelState::Idle
    }

    /// Advances the channel's life after the epoch centred at `t` (s): pull-in over and locked
    /// → tracking; code lock lost → lost; [`DROP_AFTER_S`] without lock → closed.
    fn advance(&mut self, t: f64) -> ChannelChange {
        let locked = self.lock.code_lock() && self.lock.phase_lock();
        let mut change = ChannelChange::None;
        self.state = match self.state {
            ChannelState::Acquiring { ready_at } if t >= ready_at && locked => {
                ChannelState::Tracking
            }
            ChannelState::Tracking if !self.lock.code_lock() => {
                change = ChannelChange::Lost {
                    gone_s: self.gone_since.map(|g| t - g),
                };
                ChannelState::Lost
            }
            s => s,
        };
        if self.state == ChannelState::Tracking && locked {
            self.last_lock_s = t;
        }
        if self.state != ChannelState::Idle && t - self.last_lock_s >= DROP_AFTER_S {
            self.state = ChannelState::Idle;
            change = ChannelChange::Closed;
        }
        change
    }

    /// Puts the channel's data-bit edges at the receiver epochs `≡ offset (mod 20)` (the
    /// edges the sample-level chain's satellite had, so that the hand-over is seamless).
    pub fn align_bit_edges(&mut self, offset: u64) {
        self.bit_offset = offset % 20;
    }

    /// Schedules a data-bit transition at the wrong moment: half a bit after the channel's
    /// first bit edge at or after `after` (s), 0.7 ms into that code period; returns its time.
    pub fn schedule_bit_flip(&mut self, after: f64) -> f64 {
        let k0 = (after / EPOCH_S).ceil() as u64;
        let edge = (k0..k0 + 20)
            .find(|k| (k + 20 - self.bit_offset) % 20 == 0)
            .unwrap_or(k0);
        let t = (edge + 10) as f64 * EPOCH_S + 0.7e-3;
        self.bit_flip_at = Some(t);
        t
    }

    /// The C/N0 the channel reports (measured by the core's estimator over 1 s windows, the
    /// first one 0.1 s), dB-Hz.
    pub fn reported_cn0_dbhz(&self) -> f64 {
        self.cn0_estimate
    }

    /// Whether the channel delivers an observation now: tracking with code and phase lock (as
    /// the core's adapter passes on a channel's epochs).
    pub fn delivering(&self) -> bool {
        self.state == ChannelState::Tracking && self.lock.code_lock() && self.lock.phase_lock()
    }

    /// Epoch `k` (centre time `t`) of a running channel: the observation it delivers (if it
    /// does), the epoch's noise taps of A, B, C, and what happened to the channel. `sat` is the
    /// truth (`None`: the satellite is not in the sky), `psi` the geometric phases of A, B, C
    /// (rad), `line_bias` (rad). The observation's `noise_var` is left to the caller, who
    /// measures it from the noise taps (the core's noise floor) as the sample-level chain
    /// does.
    pub fn observe(
        &mut self,
        k: u64,
        t: f64,
        sat: Option<&SatTruth>,
        psi: [f64; 3],
        line_bias: [f64; 3],
        rng: &mut ChaCha8Rng,
    ) -> (Option<SatelliteObservation<f32>>, [Iq; 3], ChannelChange) {
        let d = self.data_sign(k, t, rng);
        let received = sat.map_or([false; 3], |s| s.visible);
        if received[0] {
            self.gone_since = None;
        } else if self.gone_since.is_none() {
            self.gone_since = Some(t);
        }
        let n_pll: f64 = StandardNormal.sample(rng);
        let phi = match sat {
            Some(s) if received[0] => {
                let cn0_ref = 10f64.powf(s.cn0_dbhz[0] / 10.0);
                (PLL_BANDWIDTH_HZ / cn0_ref).sqrt() * n_pll
            }
            _ => 0.0,
        };
        let mut prompt = PromptIq::default();
        let mut reference = (0.0, 0.0);
        for p in 0..3 {
            let amplitude = match sat {
                Some(s) if received[p] => {
                    (2.0 * 10f64.powf(s.cn0_dbhz[p] / 10.0) * EPOCH_S).sqrt() * NOISE_SIGMA
                }
                _ => 0.0,
            };
            // the reference loop tracks antenna A's carrier: its prompt sits on I (± the bit)
            let theta =
                phi + (psi[p] - psi[0]) + (line_bias[p] - line_bias[0]) + self.transient(p, t);
            let ni: f64 = StandardNormal.sample(rng);
            let nq: f64 = StandardNormal.sample(rng);
            prompt.i[p] = (amplitude * d * theta.cos() + NOISE_SIGMA * ni) as f32;
            prompt.q[p] = (amplitude * d * theta.sin() + NOISE_SIGMA * nq) as f32;
            if p == 0 {
                reference = (amplitude * d * theta.cos(), amplitude * d * theta.sin());
            }
        }
        let noise = [(); 3].map(|_| noise_iq(rng, NOISE_SIGMA));
        self.measure_cn0(&prompt, &noise[0], t);
        self.update_lock(&prompt, reference, &noise[0]);
        let change = self.advance(t);
        let observation = self.delivering().then(|| SatelliteObservation {
            id: self.prn,
            los: [0.0, 0.0, 1.0],
            prompt,
            noise_var: f32::NAN,
            cn0_dbhz: self.cn0_estimate.clamp(0.0, 90.0) as f32,
        });
        (observation, noise, change)
    }

    /// The data sign of epoch `k` (centre `t`): edges every 20 epochs at the channel's offset;
    /// a scheduled transition at the wrong moment inverts the sign from then on (inside its
    /// epoch, the fraction after it counts inverted).
    fn data_sign(&mut self, k: u64, t: f64, rng: &mut ChaCha8Rng) -> f64 {
        let mut d_start = self.bit;
        if (k + 20 - self.bit_offset) % 20 == 0 {
            self.bit = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            d_start = self.bit;
        }
        let sign = if self.flipped { -1.0 } else { 1.0 };
        let t0 = t - 0.5 * EPOCH_S;
        let mut d = d_start * sign;
        if let Some(tf) = self.bit_flip_at {
            if !self.flipped && tf >= t0 && tf < t0 + EPOCH_S {
                let f = (tf - t0) / EPOCH_S;
                d = d_start * sign * (f - (1.0 - f));
                self.flipped = true;
            }
        }
        d
    }

    /// The injected phase transients of antenna `p` at `t`, rad.
    fn transient(&self, p: usize, t: f64) -> f64 {
        self.transients
            .iter()
            .filter(|tr| tr.antenna == p && t >= tr.start_s)
            .map(|tr| {
                let frac = ((t - tr.start_s) / tr.duration_s).min(1.0);
                std::f64::consts::TAU * tr.cycles * frac
            })
            .sum()
    }

    /// One epoch of the reference antenna's early, prompt, late and noise taps into the lock
    /// window; a full window updates the core's lock detector. `signal` is the prompt's
    /// noise-free part (the early and late taps carry half of it).
    fn update_lock(&mut self, prompt: &PromptIq<f32>, signal: (f64, f64), noise: &Iq) {
        let rng = &mut self.tap_rng;
        let mut tap = || {
            let (ni, nq): (f64, f64) = (StandardNormal.sample(rng), StandardNormal.sample(rng));
            Iq {
                i: (EARLY_LATE_AMPLITUDE * signal.0 + NOISE_SIGMA * ni).round() as i32,
                q: (EARLY_LATE_AMPLITUDE * signal.1 + NOISE_SIGMA * nq).round() as i32,
            }
        };
        let taps = Taps {
            early: tap(),
            prompt: Iq {
                i: prompt.i[0].round() as i32,
                q: prompt.q[0].round() as i32,
            },
            late: tap(),
            noise: *noise,
        };
        // (no samples behind these taps: no quantization floor)
        self.lock_window.add_taps(&taps, 0, true);
        if self.lock_window.count() >= self.lock_epochs {
            if let Some(e) = self.lock_window.finish(EPOCH_S as f32) {
                self.lock.update(&e);
            }
        }
    }

    /// The channel's C/N0: the core's estimator on the reference prompt and noise tap.
    fn measure_cn0(&mut self, prompt: &PromptIq<f32>, noise: &Iq, t: f64) {
        let p = Iq {
            i: prompt.i[0].round() as i32,
            q: prompt.q[0].round() as i32,
        };
        self.cn0_window.add(&p, noise);
        let window = if self.cn0_estimate > 0.0 {
            CN0_WINDOW_S
        } else {
            CN0_FIRST_WINDOW_S
        };
        if self.cn0_updated == f64::NEG_INFINITY {
            self.cn0_updated = t;
        }
        if t - self.cn0_updated >= window - 0.5 * EPOCH_S {
            if let Some(e) = self.cn0_window.finish(EPOCH_S as f32) {
                self.cn0_estimate = f64::from(e.cn0_dbhz);
            }
            self.cn0_updated = t;
        }
    }
}

/// A seeded generator for the fast path.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed ^ 0x6d69_6372_6f73_6174)
}
