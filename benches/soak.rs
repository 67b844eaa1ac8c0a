//! The million-epoch soak of the attitude receiver (issue 15): the example flight (8
//! satellites at 45 dB-Hz with thermal noise, gyro at 100 Hz) for `SOAK_EPOCHS` 1 ms epochs
//! (default 1,000,000) with, every minute of flight, a cycle of injected faults: signal
//! outages of 1 s, 30 s and 130 s (the gyro only), an epoch jump of an hour, a blocked
//! antenna for 5 s and a burst of poisoned calls (NaN and infinite prompts, noise and C/N0,
//! a NaN line of sight, infinite and implausible gyro samples, stale epochs, an epoch near
//! `u64::MAX`). The last 30 s are clean.
//!
//! Invariants (exit status 1 when one fails): every attitude output finite (quaternion and
//! covariance); every poisoned call refused and the attitude unchanged by it; valid data
//! never refused; after every outage or jump a fine attitude again within
//! [`RECOVERY_LIMIT_S`]; while fine, the error within [`FINE_ERROR_LIMIT_DEG`] of the truth;
//! the receiver fine at the end. Prints one line with the counts and the wall time.
//! Run: `cargo bench --bench soak` (release); `SOAK_EPOCHS=100000` for a shorter run.

use std::process::ExitCode;
use std::time::Instant;

use gnss_attitude::attitude::one_stage::SatelliteObservation;
use gnss_attitude::receiver::example::ExampleFlight;
use gnss_attitude::receiver::{AttitudeReceiver, AttitudeSource, ReceiverEvent, SatelliteAiding};

/// Longest time from the end of an outage or a jump to a fine attitude again, s (the cold
/// start takes about 0.7 s; a window or two of margin for a refused fix).
const RECOVERY_LIMIT_S: f64 = 5.0;

/// Largest error of a fine attitude against the truth, degrees (its σ is about 0.02°).
const FINE_ERROR_LIMIT_DEG: f32 = 1.0;

/// Epochs of clean flight between two faults of the cycle (10 s).
const CLEAN_EPOCHS: u64 = 10_000;

/// The clean flight at the end, epochs (30 s).
const FINAL_CLEAN_EPOCHS: u64 = 30_000;

/// One fault of the cycle.
#[derive(Clone, Copy, Debug)]
enum Fault {
    /// No signal for this many epochs (the gyro keeps running).
    Outage(u64),
    /// The epoch number jumps ahead by this many epochs.
    Jump(u64),
    /// Antenna C sees no signal for this many epochs.
    Blocked(u64),
    /// A burst of poisoned calls.
    Poison,
}

const CYCLE: [Fault; 6] = [
    Fault::Outage(1_000),
    Fault::Poison,
    Fault::Outage(30_000),
    Fault::Jump(3_600_000),
    Fault::Outage(130_000),
    Fault::Blocked(5_000),
];

#[derive(Debug, Default)]
struct Tally {
    epochs: u64,
    outputs: u64,
    non_finite: u64,
    refusals: u64,
    poison_accepted: u64,
    poison_changed: u64,
    valid_refused: u64,
    cold_restarts: u64,
    fine_epochs: u64,
    fine_too_wrong: u64,
    max_fine_error_deg: f32,
    within_3_sigma: u64,
    recoveries: u64,
    slow_recoveries: u64,
    max_recovery_s: f64,
}

/// A call that must be refused: true when it was.
type PoisonedCall = Box<dyn Fn(&mut AttitudeReceiver) -> bool>;

struct Soak {
    flight: ExampleFlight,
    receiver: AttitudeReceiver,
    /// The next epoch to fly.
    k: u64,
    tally: Tally,
    /// Epoch from which a fine attitude is awaited (after an outage or a jump).
    awaiting: Option<u64>,
}

impl Soak {
    fn new(seed: u64) -> Self {
        let receiver = AttitudeReceiver::new(ExampleFlight::config(true))
            .unwrap_or_else(|e| panic!("the example configuration: {e}"));
        Self {
            flight: ExampleFlight::new(seed),
            receiver,
            k: 0,
            tally: Tally::default(),
            awaiting: None,
        }
    }

    /// Flies `n` epochs of valid data, checking every epoch's output.
    fn fly(&mut self, n: u64) {
        for _ in 0..n {
            let k = self.k;
            if self.flight.fly(&mut self.receiver, k, k + 1).is_err() {
                self.tally.valid_refused += 1;
            }
            self.k += 1;
            self.tally.epochs += 1;
            self.check(k);
        }
    }

    /// The output after epoch `k`: finite, and while fine close to the truth.
    fn check(&mut self, k: u64) {
        while let Some(e) = self.receiver.pop_event() {
            if matches!(e, ReceiverEvent::AttitudeLost { .. }) {
                self.tally.cold_restarts += 1;
            }
        }
        let att = self.receiver.attitude();
        let q = att.q_rb;
        let finite = [q.w, q.x, q.y, q.z].iter().all(|v| v.is_finite())
            && att.covariance.iter().all(|v| v.is_finite());
        if !finite {
            self.tally.non_finite += 1;
            return;
        }
        if att.source == AttitudeSource::None {
            return;
        }
        self.tally.outputs += 1;
        if att.source != AttitudeSource::Fine {
            return;
        }
        if let Some(from) = self.awaiting.take() {
            let s = (k - from) as f64 * 1e-3;
            self.tally.recoveries += 1;
            self.tally.max_recovery_s = self.tally.max_recovery_s.max(s);
            if s > RECOVERY_LIMIT_S {
                self.tally.slow_recoveries += 1;
            }
        }
        let error = att.q_rb.angle_to(&self.flight.attitude(att.epoch));
        let sigma = att.covariance.trace().max(0.0).sqrt();
        self.tally.fine_epochs += 1;
        self.tally.max_fine_error_deg = self.tally.max_fine_error_deg.max(error.to_degrees());
        if error.to_degrees() > FINE_ERROR_LIMIT_DEG {
            self.tally.fine_too_wrong += 1;
        }
        if error <= 3.0 * sigma {
            self.tally.within_3_sigma += 1;
        }
    }

    /// The fine attitude is awaited again from epoch `k`; while it is not back, the outputs
    /// are still checked every epoch.
    fn await_fine(&mut self) {
        if let Some(from) = self.awaiting.take() {
            // the previous fault's recovery never came before this one
            let s = (self.k - from) as f64 * 1e-3;
            self.tally.slow_recoveries += u64::from(s > RECOVERY_LIMIT_S);
        }
        self.awaiting = Some(self.k);
    }

    fn inject(&mut self, fault: Fault) {
        match fault {
            Fault::Outage(n) => {
                let (from, to) = (self.k, self.k + n);
                if self.flight.coast(&mut self.receiver, from, to).is_err() {
                    self.tally.valid_refused += 1;
                }
                self.k = to;
                self.tally.epochs += n;
                self.check(to - 1);
                self.await_fine();
            }
            Fault::Jump(n) => {
                self.k += n;
                self.await_fine();
            }
            Fault::Blocked(n) => {
                self.flight.antenna_gain[2] = 0.0;
                self.fly(n);
                self.flight.antenna_gain[2] = 1.0;
            }
            Fault::Poison => self.poison(),
        }
    }

    /// One burst of poisoned calls at the current epoch: each must be refused and leave the
    /// attitude as it was.
    fn poison(&mut self) {
        let k = self.k;
        let good: SatelliteObservation<f32> = self.flight.observations(k)[0];
        let mut calls: Vec<PoisonedCall> = Vec::new();
        for (i, v) in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY]
            .into_iter()
            .enumerate()
        {
            let mut o = good;
            o.prompt.i[i] = v;
            calls.push(Box::new(move |r| r.push_observation(k, &o).is_err()));
            let mut o = good;
            o.noise_var = v;
            calls.push(Box::new(move |r| r.push_observation(k, &o).is_err()));
            let mut o = good;
            o.cn0_dbhz = v;
            calls.push(Box::new(move |r| r.push_observation(k, &o).is_err()));
            calls.push(Box::new(move |r| {
                r.push_gyro_increment(&[v, 0.0, 0.0]).is_err()
            }));
            let aiding = SatelliteAiding {
                prn: good.id,
                epoch: k,
                los: [v, 0.0, 1.0],
                los_rate: [0.0; 3],
            };
            calls.push(Box::new(move |r| r.set_aiding(&[aiding]).is_err()));
        }
        let mut o = good;
        o.cn0_dbhz = 1e30;
        calls.push(Box::new(move |r| r.push_observation(k, &o).is_err()));
        o = good;
        o.noise_var = -1e-30;
        calls.push(Box::new(move |r| r.push_observation(k, &o).is_err()));
        calls.push(Box::new(|r| {
            r.push_gyro_increment(&[2.0, 0.0, 0.0]).is_err()
        }));
        calls.push(Box::new(move |r| {
            r.push_observation(u64::MAX, &good).is_err()
        }));
        let stale = k.saturating_sub(500);
        calls.push(Box::new(move |r| r.push_observation(stale, &good).is_err()));
        for call in &calls {
            let before = self.receiver.attitude();
            if call(&mut self.receiver) {
                self.tally.refusals += 1;
            } else {
                self.tally.poison_accepted += 1;
            }
            if self.receiver.attitude() != before {
                self.tally.poison_changed += 1;
            }
        }
    }
}

fn main() -> ExitCode {
    let total: u64 = std::env::var("SOAK_EPOCHS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let start = Instant::now();
    let mut soak = Soak::new(15);
    let mut cycle = CYCLE.iter().cycle();
    while soak.tally.epochs + FINAL_CLEAN_EPOCHS < total {
        let left = total - FINAL_CLEAN_EPOCHS - soak.tally.epochs;
        soak.fly(CLEAN_EPOCHS.min(left));
        let fault = *cycle.next().unwrap_or(&Fault::Poison);
        let fits = match fault {
            Fault::Outage(n) | Fault::Blocked(n) => {
                soak.tally.epochs + n + FINAL_CLEAN_EPOCHS <= total
            }
            Fault::Jump(_) | Fault::Poison => true,
        };
        if fits && soak.tally.epochs + FINAL_CLEAN_EPOCHS < total {
            soak.inject(fault);
        }
    }
    soak.fly(total.saturating_sub(soak.tally.epochs));
    let wall = start.elapsed().as_secs_f64();
    let t = &soak.tally;
    let source = soak.receiver.attitude().source;
    let recovered = soak.awaiting.is_none();
    println!(
        "soak: {} epochs, {} attitude outputs, {} non-finite outputs, {} refusals \
         ({} poisoned calls accepted, {} changed the attitude; {} valid calls refused), \
         {} cold restarts, {} recoveries (slowest {:.2} s, {} over {RECOVERY_LIMIT_S} s), \
         fine epochs {} (error <= 3 sigma in {:.2} %, max error {:.3} deg, {} over \
         {FINE_ERROR_LIMIT_DEG} deg), final source {:?}, wall time {:.1} s",
        t.epochs,
        t.outputs,
        t.non_finite,
        t.refusals,
        t.poison_accepted,
        t.poison_changed,
        t.valid_refused,
        t.cold_restarts,
        t.recoveries,
        t.max_recovery_s,
        t.slow_recoveries,
        t.fine_epochs,
        100.0 * t.within_3_sigma as f64 / t.fine_epochs.max(1) as f64,
        t.max_fine_error_deg,
        t.fine_too_wrong,
        source,
        wall,
    );
    let ok = t.non_finite == 0
        && t.poison_accepted == 0
        && t.poison_changed == 0
        && t.valid_refused == 0
        && t.slow_recoveries == 0
        && t.fine_too_wrong == 0
        && recovered
        && source == AttitudeSource::Fine;
    if ok {
        ExitCode::SUCCESS
    } else {
        println!("soak: FAIL (an invariant above)");
        ExitCode::FAILURE
    }
}
