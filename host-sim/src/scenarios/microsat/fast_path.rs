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
//! The channel's life is emulated: a satellite rising above the reference antenna's mask is
//! searched at the next whole second and delivers epochs after the chain's refinement and
//! pull-in (256 ms + 300 ms); one that sets keeps delivering noise for the 100 ms the lock
//! detector needs to notice, then stops.

use gnss_attitude::attitude::one_stage::{PromptIq, SatelliteObservation};
use gnss_attitude::signal::correlator::Iq;
use gnss_attitude::tracking::cn0::PowerWindow;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::world::SatTruth;

/// Noise standard deviation of each correlator component, counts (an arbitrary scale the
/// receiver normalizes away).
pub const NOISE_SIGMA: f64 = 40.0;
/// Epoch (code period), s.
pub const EPOCH_S: f64 = 1e-3;
/// Refinement and pull-in of the chain after a hand-over, s.
pub const PULL_IN_S: f64 = 0.556;
/// Time the lock detector needs to declare a vanished signal lost, s.
pub const LOSS_S: f64 = 0.1;
/// PLL noise bandwidth of the reference loop, Hz.
pub const PLL_BANDWIDTH_HZ: f64 = 15.0;

/// Where an emulated channel is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ChannelState {
    /// No channel.
    Idle,
    /// Searched; delivers from `ready_at` (s).
    Acquiring {
        /// First time with observations, s.
        ready_at: f64,
    },
    /// Delivering observations.
    Tracking,
    /// The signal vanished at the reference antenna; delivering noise until `until` (s).
    Losing {
        /// When the channel declares the loss, s.
        until: f64,
    },
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
}

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

impl EmulatedChannel {
    /// An idle channel.
    pub fn new(prn: u8, rng: &mut ChaCha8Rng) -> Self {
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
        }
    }

    /// Advances the channel's life to `t` given whether the reference antenna sees the
    /// satellite (an idle channel that sees it is searched at the next whole second).
    pub fn advance(&mut self, t: f64, reference_sees: bool) {
        self.state = match self.state {
            ChannelState::Idle if reference_sees => ChannelState::Acquiring {
                // the receiver searches new satellites every whole second
                ready_at: t.ceil().max(t) + PULL_IN_S,
            },
            ChannelState::Acquiring { .. } if !reference_sees => ChannelState::Idle,
            ChannelState::Acquiring { ready_at } if t >= ready_at => ChannelState::Tracking,
            ChannelState::Tracking if !reference_sees => ChannelState::Losing { until: t + LOSS_S },
            ChannelState::Losing { .. } if reference_sees => ChannelState::Tracking,
            ChannelState::Losing { until } if t >= until => ChannelState::Idle,
            s => s,
        };
    }

    /// Starts the channel as if handed over at `t0` (the sample-level chain's satellites
    /// continuing on the fast path).
    pub fn continue_tracking(&mut self) {
        self.state = ChannelState::Tracking;
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

    /// Whether the channel delivers an observation now.
    pub fn delivering(&self) -> bool {
        matches!(
            self.state,
            ChannelState::Tracking | ChannelState::Losing { .. }
        )
    }

    /// The observation of epoch `k` (centre time `t`) and the epoch's noise taps of A, B, C:
    /// `sat` the truth, `psi` the geometric phases of A, B, C (rad), `line_bias` (rad). The
    /// observation's `noise_var` is left to the caller, who measures it from the noise taps
    /// (the core's noise floor) as the sample-level chain does.
    pub fn observe(
        &mut self,
        k: u64,
        t: f64,
        sat: &SatTruth,
        psi: [f64; 3],
        line_bias: [f64; 3],
        rng: &mut ChaCha8Rng,
    ) -> (SatelliteObservation<f32>, [Iq; 3]) {
        // data bit: edges every 20 epochs at the channel's offset
        let mut d_start = self.bit;
        if (k + 20 - self.bit_offset) % 20 == 0 {
            self.bit = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            d_start = self.bit;
        }
        let sign = if self.flipped { -1.0 } else { 1.0 };
        // a transition at the wrong moment: the sign inverts at bit_flip_at, inside this epoch
        let t0 = t - 0.5 * EPOCH_S;
        let mut d = d_start * sign;
        if let Some(tf) = self.bit_flip_at {
            if !self.flipped && tf >= t0 && tf < t0 + EPOCH_S {
                let f = (tf - t0) / EPOCH_S;
                d = d_start * sign * (f - (1.0 - f));
                self.flipped = true;
            }
        }
        let cn0_ref = 10f64.powf(sat.cn0_dbhz[0] / 10.0);
        let pll_sigma = (PLL_BANDWIDTH_HZ / cn0_ref).sqrt();
        let n_pll: f64 = StandardNormal.sample(rng);
        let phi = pll_sigma * n_pll;
        let mut prompt = PromptIq::default();
        for p in 0..3 {
            let amplitude = if sat.visible[p] {
                (2.0 * 10f64.powf(sat.cn0_dbhz[p] / 10.0) * EPOCH_S).sqrt() * NOISE_SIGMA
            } else {
                0.0
            };
            let mut transient = 0.0;
            for tr in &self.transients {
                if tr.antenna == p && t >= tr.start_s {
                    let frac = ((t - tr.start_s) / tr.duration_s).min(1.0);
                    transient += std::f64::consts::TAU * tr.cycles * frac;
                }
            }
            // the reference loop tracks antenna A's carrier: its prompt sits on I (± the bit)
            let theta = phi + (psi[p] - psi[0]) + (line_bias[p] - line_bias[0]) + transient;
            let ni: f64 = StandardNormal.sample(rng);
            let nq: f64 = StandardNormal.sample(rng);
            prompt.i[p] = (amplitude * d * theta.cos() + NOISE_SIGMA * ni) as f32;
            prompt.q[p] = (amplitude * d * theta.sin() + NOISE_SIGMA * nq) as f32;
        }
        let noise = [(); 3].map(|_| noise_iq(rng, NOISE_SIGMA));
        self.measure_cn0(&prompt, &noise[0], t);
        let observation = SatelliteObservation {
            id: self.prn,
            los: [0.0, 0.0, 1.0],
            prompt,
            noise_var: f32::NAN,
            cn0_dbhz: self.cn0_estimate.clamp(0.0, 90.0) as f32,
        };
        (observation, noise)
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
