//! Outcome gates: the estimators on their embedded data must succeed and land near the truth.
//!
//! Each gate prints one `selfcheck <name>: PASS|FAIL ...` line and returns whether it passed:
//!
//! * **snapshot**: paper 002's solver on the example epoch ([`example::ranges`], 2 baselines x
//!   8 satellites, 4 mm range differences) returns a solution whose attitude error against
//!   [`example::attitude`] is within [`SIGMA_FACTOR`] times the solution's own 1σ
//!   (`sqrt(trace P)`) and below [`SNAPSHOT_LIMIT_DEG`];
//! * **ambiguity**: the constrained integer search on the example's raw single differences
//!   ([`example::phases`], 3 mm carrier, 0.3 m code) fixes every one of the 16 integers to its
//!   true value, and its attitude meets the same two limits;
//! * **receiver**: the [`AttitudeReceiver`](gnss_attitude::receiver::AttitudeReceiver) on the
//!   example flight ([`budget::receiver_budgets`]) refused none of its calls, ends in
//!   [`AttitudeSource::Fine`], and its attitude error against the flight's truth is below
//!   [`RECEIVER_LIMIT_DEG`].
//!
//! With `wrong-expected` on the semihosting command line ([`crate::cmdline`]) every truth is
//! perturbed (the attitudes rotated by [`crate::cmdline::WRONG_TRUTH_DEG`], the integers shifted by one
//! cycle): every gate must then fail, which `.ci/run` checks.

use cortex_m_semihosting::hprintln;
use gnss_attitude::attitude::example;
use gnss_attitude::receiver::AttitudeSource;

use crate::budget;

/// Largest attitude error of the snapshot solution and of the integer fix accepted, in units
/// of the solution's own 1σ of the total rotation error (`sqrt(trace P)`).
pub const SIGMA_FACTOR: f32 = 4.0;
/// Largest attitude error of the snapshot solution and of the integer fix accepted, degrees
/// (1 m baselines, 8 satellites: their 1σ is a few hundredths of a degree).
pub const SNAPSHOT_LIMIT_DEG: f32 = 0.3;
/// Largest attitude error of the receiver at the end of the example flight, degrees.
pub const RECEIVER_LIMIT_DEG: f32 = 0.05;
use crate::cmdline::gate_truth as truth;

/// The true integer of baseline `i`, satellite `j` as the gates see it (one cycle off with the
/// `wrong-expected` on the command line).
fn true_integer(i: usize, j: usize) -> i32 {
    example::ambiguity(i, j) + i32::from(crate::cmdline::wrong_expected())
}

fn verdict(pass: bool) -> &'static str {
    if pass {
        "PASS"
    } else {
        "FAIL"
    }
}

/// The attitude error, its 1σ and the limit it must meet (degrees): the smaller of
/// [`SIGMA_FACTOR`] σ and [`SNAPSHOT_LIMIT_DEG`].
fn snapshot_error(
    solution: &gnss_attitude::attitude::snapshot::SnapshotSolution<f32>,
) -> (f32, f32, f32) {
    let error_deg = solution
        .q_rb
        .angle_to(&truth(example::attitude().to_quaternion()))
        .to_degrees();
    let sigma_deg = nalgebra::ComplexField::sqrt(solution.covariance.trace().max(0.0)).to_degrees();
    (
        error_deg,
        sigma_deg,
        (SIGMA_FACTOR * sigma_deg).min(SNAPSHOT_LIMIT_DEG),
    )
}

/// Paper 002's snapshot solver on the example epoch.
#[inline(never)]
pub fn snapshot() -> bool {
    let (Ok(solver), Ok(ranges)) = (example::solver(), example::ranges(8, 1)) else {
        hprintln!("selfcheck snapshot: FAIL example setup refused");
        return false;
    };
    match solver.solve(&ranges) {
        Ok(s) => {
            let (error_deg, sigma_deg, limit_deg) = snapshot_error(&s);
            let pass = error_deg.is_finite() && error_deg <= limit_deg;
            hprintln!(
                "selfcheck snapshot: {} 2 baselines x 8 satellites solved, attitude error {} deg, 1 sigma {} deg (limit {} deg = min({} sigma, {} deg)), chi2 {} / {} dof, {} iterations",
                verdict(pass),
                error_deg,
                sigma_deg,
                limit_deg,
                SIGMA_FACTOR,
                SNAPSHOT_LIMIT_DEG,
                s.chi_square,
                s.dof,
                s.iterations
            );
            pass
        }
        Err(e) => {
            hprintln!("selfcheck snapshot: FAIL solver refused: {:?}", e);
            false
        }
    }
}

/// The constrained ambiguity resolver on the example's raw single differences.
#[inline(never)]
pub fn ambiguity() -> bool {
    let (Ok(resolver), Ok(phases)) = (example::resolver(), example::phases(8, 1)) else {
        hprintln!("selfcheck ambiguity: FAIL example setup refused");
        return false;
    };
    match resolver.resolve(&phases) {
        Ok(fix) => {
            let mut wrong = 0u32;
            for (i, row) in fix.ambiguities.iter().enumerate() {
                for (j, n) in row.iter().take(example::SKY.len()).enumerate() {
                    wrong += u32::from(*n != true_integer(i, j));
                }
            }
            let (error_deg, sigma_deg, limit_deg) = snapshot_error(&fix.solution);
            let pass = wrong == 0 && error_deg.is_finite() && error_deg <= limit_deg;
            hprintln!(
                "selfcheck ambiguity: {} {} of 16 integers wrong (2 baselines x 8 satellites), ratio {}, attitude error {} deg, 1 sigma {} deg (limit {} deg), {} nodes",
                verdict(pass),
                wrong,
                fix.ratio,
                error_deg,
                sigma_deg,
                limit_deg,
                fix.nodes
            );
            pass
        }
        Err(e) => {
            hprintln!("selfcheck ambiguity: FAIL resolver refused: {:?}", e);
            false
        }
    }
}

/// The receiver at the end of the example flight (run, and measured, by
/// [`budget::receiver_budgets`]).
pub fn receiver(outcome: Option<&budget::ReceiverOutcome>) -> bool {
    let Some(o) = outcome else {
        hprintln!("selfcheck receiver: FAIL the example flight did not run");
        return false;
    };
    let truth_q = truth(o.truth);
    let error_deg = o.attitude.angle_to(&truth_q).to_degrees();
    let fine = o.source == AttitudeSource::Fine;
    let pass = o.refusals == 0 && fine && error_deg.is_finite() && error_deg < RECEIVER_LIMIT_DEG;
    hprintln!(
        "selfcheck receiver: {} after {} epochs (attitude of epoch {}) source {:?} (must be Fine), attitude error {} deg (limit {} deg), {} calls refused",
        verdict(pass),
        budget::FLIGHT_EPOCHS,
        o.epoch,
        o.source,
        error_deg,
        RECEIVER_LIMIT_DEG,
        o.refusals
    );
    pass
}
