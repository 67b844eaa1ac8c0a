//! Where each estimated quantity sits in the filter's state vector, as selection matrices.
//!
//! The filter never indexes its state by a runtime number: every move between the parameter
//! space (α, β, γ, `b_B`, `b_C`) and the state space is a product with one of these 0/1
//! matrices, so an index cannot fall out of range and a quantity that is not estimated reads
//! as what it is, absent (a zero row).

use nalgebra::{SMatrix, SVector};

use super::config::OneStageConfig;
use super::information::PARAMETERS;
use crate::Real;

/// The state layout for a configuration: the estimated angles first, then their rates, then
/// the two line biases if they are estimated. With all of them on,
/// `X = [α, β, γ, α̇, β̇, γ̇, b_B, b_C]`; for the paper's β-only filter `X = [β, β̇]`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StateLayout<T, const N: usize> {
    /// State index of each parameter α, β, γ, `b_B`, `b_C` (`None` when not estimated).
    pub parameter: [Option<usize>; PARAMETERS],
    /// State index of the rates α̇, β̇, γ̇.
    pub rate: [Option<usize>; 3],
    /// `c` of eq. (9): `c X` is the parameter vector (α, β, γ, `b_B`, `b_C`), zero where a
    /// parameter is not estimated.
    pub c: SMatrix<T, PARAMETERS, N>,
    /// The angles' rows of `c`: `S_α X = (α, β, γ)`.
    pub angles: SMatrix<T, 3, N>,
    /// `S_ω X = (α̇, β̇, γ̇)`.
    pub rates: SMatrix<T, 3, N>,
    /// `S_b X = (b_B, b_C)`.
    pub biases: SMatrix<T, 2, N>,
}

impl<T: Real, const N: usize> StateLayout<T, N> {
    /// The layout of `config` in a state of dimension `N`; `None` when `N` is not the
    /// dimension the configuration needs ([`OneStageConfig::state_dimension`]).
    pub fn of(config: &OneStageConfig<T>) -> Option<Self> {
        let (parameter, rate, dimension) = indices(config);
        if dimension != N {
            return None;
        }
        let select = |idx: &[Option<usize>], r: usize, col: usize| {
            if idx.get(r).copied().flatten() == Some(col) {
                T::one()
            } else {
                T::zero()
            }
        };
        let c = SMatrix::from_fn(|r, col| select(&parameter, r, col));
        Some(Self {
            parameter,
            rate,
            c,
            angles: SMatrix::from_fn(|r, col| select(&parameter, r, col)),
            rates: SMatrix::from_fn(|r, col| select(&rate, r, col)),
            biases: SMatrix::from_fn(|r, col| select(&parameter, r + 3, col)),
        })
    }

    /// The parameters that are estimated (α, β, γ, `b_B`, `b_C`).
    pub fn active(&self) -> [bool; PARAMETERS] {
        self.parameter.map(|p| p.is_some())
    }

    /// `Sᵀ diag(d) S` for a selection `S`: a diagonal state matrix with `d` on the selected
    /// states (process noise, variances).
    pub fn spread<const K: usize>(s: &SMatrix<T, K, N>, d: &SVector<T, K>) -> SMatrix<T, N, N> {
        s.transpose() * SMatrix::<T, K, K>::from_diagonal(d) * s
    }
}

/// The state dimension `config` needs: twice the estimated angles, plus two with line
/// biases.
pub(super) fn dimension_of<T>(config: &OneStageConfig<T>) -> usize {
    indices(config).2
}

/// Parameter and rate indices, and the dimension they need.
fn indices<T>(
    config: &OneStageConfig<T>,
) -> ([Option<usize>; PARAMETERS], [Option<usize>; 3], usize) {
    let angles = config.estimate.as_array();
    let mut parameter = [None; PARAMETERS];
    let mut rate = [None; 3];
    let mut next = 0usize;
    for (slot, &on) in parameter.iter_mut().zip(angles.iter()) {
        if on {
            *slot = Some(next);
            next = next.saturating_add(1); // (at most PARAMETERS + 3)
        }
    }
    for (slot, &on) in rate.iter_mut().zip(angles.iter()) {
        if on {
            *slot = Some(next);
            next = next.saturating_add(1); // (at most PARAMETERS + 3)
        }
    }
    if config.line_bias_states {
        for slot in parameter.iter_mut().skip(3) {
            *slot = Some(next);
            next = next.saturating_add(1); // (at most PARAMETERS + 3)
        }
    }
    (parameter, rate, next)
}
