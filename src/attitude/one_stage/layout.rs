//! Where each estimated quantity sits in the filter's state vector.

use super::config::OneStageConfig;
use super::information::PARAMETERS;

/// The state layout for a configuration: the estimated angles first, then their rates, then
/// the two line biases if they are estimated. With all of them on,
/// `X = [α, β, γ, α̇, β̇, γ̇, b_B, b_C]`; for the paper's β-only filter `X = [β, β̇]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StateLayout {
    /// State index of each parameter α, β, γ, `b_B`, `b_C` (`None` when not estimated): the
    /// matrix `c` of eq. (9) as index lists.
    pub parameter: [Option<usize>; PARAMETERS],
    /// State index of the rates α̇, β̇, γ̇.
    pub rate: [Option<usize>; 3],
    /// State dimension the configuration needs.
    pub dimension: usize,
}

impl StateLayout {
    /// The layout of `config`.
    pub fn of<T>(config: &OneStageConfig<T>) -> Self {
        let angles = config.estimate.as_array();
        let mut parameter = [None; PARAMETERS];
        let mut rate = [None; 3];
        let mut next = 0;
        for (slot, &on) in parameter.iter_mut().zip(angles.iter()) {
            if on {
                *slot = Some(next);
                next += 1;
            }
        }
        for (slot, &on) in rate.iter_mut().zip(angles.iter()) {
            if on {
                *slot = Some(next);
                next += 1;
            }
        }
        if config.line_bias_states {
            for slot in parameter.iter_mut().skip(3) {
                *slot = Some(next);
                next += 1;
            }
        }
        Self {
            parameter,
            rate,
            dimension: next,
        }
    }

    /// The parameters that are estimated (α, β, γ, `b_B`, `b_C`).
    pub fn active(&self) -> [bool; PARAMETERS] {
        self.parameter.map(|p| p.is_some())
    }
}
