//! `gyro-cal --variant gnss-ref`.

use super::{Outcome, RunContext};

pub(crate) fn run(_ctx: &RunContext) -> anyhow::Result<Outcome> {
    anyhow::bail!("not yet")
}
