//! `snapshot`: paper 002's single-epoch attitude from carrier-phase range differences, with
//! integer ambiguity resolution.
//!
//! * `paper` ([`paper`]): the paper's case (1 m triangle, 3 satellites at 60/45/30° elevation,
//!   heading 180°, 4 mm per single difference, ambiguities known), Monte Carlo against the
//!   Cramér–Rao bound host-sim computes for the same geometry, and against the paper's printed
//!   mean errors; the printed algorithm with a pseudo-inverse is run alongside to show its bias.
//! * `ambiguity` ([`ambiguity`]): the same array on a real GPS sky (bundled YUMA almanac, 6–10
//!   satellites), 3 mm phase and 0.3 m code per single difference, random attitudes, unknown
//!   integer ambiguities: the constrained resolver against unconstrained LAMBDA and
//!   float-then-round.
//! * `four-antenna` ([`four_antenna`]): a 1 m tetrahedron, where the paper's formula (16) can
//!   run, against the general solver, at carrier (4 mm) and code (0.3 m) noise.

use super::{Outcome, RunContext, Scenario, Variant, Variants};

pub mod ambiguity;
pub mod common;
pub mod four_antenna;
pub mod paper;

/// A variant's run.
type Runner = fn(&RunContext) -> anyhow::Result<Outcome>;

/// The scenario.
pub const SCENARIO: Scenario = Scenario {
    name: "snapshot",
    about:
        "Paper 002: snapshot attitude from carrier-phase range differences, ambiguity resolution",
    variants: &Variants::<Runner> {
        list: &[
            Variant::new(
                "paper",
                "1 m triangle, 3 sats el 60/45/30, heading 180, 4 mm, vs CRB and the paper",
                paper::run,
            ),
            Variant::new(
                "ambiguity",
                "real GPS sky, 6-10 sats, 3 mm / 0.3 m, unknown integers, vs LAMBDA and rounding",
                ambiguity::run,
            ),
            Variant::new(
                "four-antenna",
                "1 m tetrahedron: the paper's formula (16) vs the general solver",
                four_antenna::run,
            ),
        ],
        run: |run, ctx| run(ctx),
    },
};
