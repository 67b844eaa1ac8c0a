//! Pull-in and false-lock detection from the normalized coherent power.
//!
//! The likelihood of eq. (15) has, besides its peak at the true attitude, secondary peaks
//! where the phase differences of some satellites wrap by whole cycles. A loop that starts too
//! far away can settle on one and would then report a confident, wrong attitude. At a wrong
//! peak the antennas of at least some satellites are not phase-aligned after derotation by the
//! estimated phases, which the **alignment**
//!
//! ```text
//!        Σ_i (X_i² − 6)
//! η = ─────────────────────────   (noise units, σ = 1 per component)
//!      Σ_i 3 (Σ_P |z_P,i|² − 6)
//! ```
//!
//! measures: numerator and denominator are unbiased estimates of `Σ_i A_i² |Σ_P e^{jδ_{P,i}}|²`
//! and `9 Σ_i A_i²` (`δ` the phase errors), so `η = 1` at the true attitude whatever the C/N0,
//! and `η < 1` elsewhere. For the paper's geometry G1 with eight satellites the secondary peaks
//! of β have `η ≤ 0.72`, with the first two satellites only `η ≤ 0.84` (besides two peaks at
//! ±52° with `η = 0.99`, which no statistic of two satellites can tell from the truth).
//!
//! The numerator and denominator are low-passed separately (time constant `τ`) and the ratio is
//! compared with two thresholds. Alignment alone would declare lock while a loop is still
//! sliding down the main peak (`η ≥ 0.9` holds within about ±1.3° of the truth for G1), so
//! lock also requires the loop to have **settled**: the normalized discriminator
//! `v = J_αα⁻¹ u_α` (the per-epoch estimate of the remaining angle error), low-passed with the
//! same `τ` to `v̄`, must be consistent with zero, `s = v̄ᵀ J_αα v̄ · 2τ/T ≤ settle_threshold`
//! (`s` is at most χ² with as many degrees of freedom as estimated angles; the loop's own
//! high-pass response makes it smaller).
//!
//! * [`LockStatus::PullIn`] after (re)initialization, until `η̄ ≥ lock_threshold` and
//!   `s ≤ settle_threshold` have held together for `hold_s`; then [`LockStatus::Locked`].
//! * [`LockStatus::FalseLock`] when pull-in has not succeeded within `pull_in_timeout_s`, or
//!   when a locked filter's `η̄` falls below `unlock_threshold`. A flagged filter returns to
//!   `Locked` only by passing the lock test again. Flight software should re-initialize it
//!   (from the snapshot solver) rather than use its attitude.

use nalgebra::{Matrix3, Vector3};

use crate::{real, Real};

/// The detector's verdict on the current estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LockStatus {
    /// Pulling in after (re)initialization: not yet shown to be at the true peak.
    PullIn,
    /// Phase-aligned on all satellites: the estimate is at the true peak.
    Locked,
    /// Not shown to be at the true peak within the pull-in time (a false lock on a secondary
    /// peak, or a pull-in too slow to trust), or alignment lost after lock: the attitude must
    /// not be used. Leaves this state only by passing the lock test again.
    FalseLock,
}

/// Thresholds and times of the detector.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LockConfig<T = f32> {
    /// Low-pass time constant `τ` of the power sums, s.
    pub time_constant_s: T,
    /// `η̄` needed to declare lock, in `(0, 1]`.
    pub lock_threshold: T,
    /// `η̄` below which a locked filter is flagged, in `(0, lock_threshold]`.
    pub unlock_threshold: T,
    /// How long `η̄ ≥ lock_threshold` must hold before lock is declared, s.
    pub hold_s: T,
    /// Pull-in time after which a filter not yet locked is flagged, s.
    pub pull_in_timeout_s: T,
    /// Largest settle statistic `s` at which lock may be declared (χ² scale).
    pub settle_threshold: T,
}

impl<T: Real> Default for LockConfig<T> {
    /// `τ` = 50 ms, lock at `η̄ ≥ 0.9` and `s ≤ 16.27` (χ²₃ at 99.9 %) held 100 ms, flag
    /// below 0.85 or after 1.5 s of pull-in.
    fn default() -> Self {
        Self {
            time_constant_s: real(0.05),
            lock_threshold: real(0.9),
            unlock_threshold: real(0.85),
            hold_s: real(0.1),
            pull_in_timeout_s: real(1.5),
            settle_threshold: real(16.27),
        }
    }
}

impl<T: Real> LockConfig<T> {
    pub(crate) fn is_valid(&self) -> bool {
        let all_finite = [
            self.time_constant_s,
            self.lock_threshold,
            self.unlock_threshold,
            self.hold_s,
            self.pull_in_timeout_s,
            self.settle_threshold,
        ]
        .iter()
        .all(|v| v.is_finite());
        all_finite
            && self.time_constant_s > T::zero()
            && self.lock_threshold > T::zero()
            && self.lock_threshold <= T::one()
            && self.unlock_threshold > T::zero()
            && self.unlock_threshold <= self.lock_threshold
            && self.hold_s >= T::zero()
            && self.pull_in_timeout_s > T::zero()
            && self.settle_threshold > T::zero()
    }
}

/// The detector's state.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LockDetector<T = f32> {
    coherent: T,
    aligned: T,
    /// Low-passed normalized angle discriminator `v̄`, rad.
    settle: [T; 3],
    /// `s = v̄ᵀ J_αα v̄ · 2τ/T` of the last epoch.
    settle_statistic: T,
    primed: bool,
    status: LockStatus,
    /// Epochs since (re)initialization (saturating).
    epochs: u32,
    /// Consecutive epochs with `η̄ ≥ lock_threshold`.
    above: u32,
    gain: T,
    hold_epochs: u32,
    timeout_epochs: u32,
    lock_threshold: T,
    unlock_threshold: T,
    settle_threshold: T,
}

fn epochs_of<T: Real>(seconds: T, epoch_s: T) -> u32 {
    let n = (seconds / epoch_s).ceil();
    if n >= real(f64::from(u32::MAX)) {
        u32::MAX
    } else if n > T::zero() {
        // exact: n is an integer below 2³², and f64/f32 convert it to u32 without rounding
        nalgebra::try_convert::<T, f64>(n).map_or(u32::MAX, |v| v as u32)
    } else {
        0
    }
}

impl<T: Real> LockDetector<T> {
    /// A detector in [`LockStatus::PullIn`] for epochs of `epoch_s` seconds (config already
    /// validated).
    pub(crate) fn new(config: &LockConfig<T>, epoch_s: T) -> Self {
        Self {
            coherent: T::zero(),
            aligned: T::zero(),
            settle: [T::zero(); 3],
            settle_statistic: T::zero(),
            primed: false,
            status: LockStatus::PullIn,
            epochs: 0,
            above: 0,
            gain: (epoch_s / config.time_constant_s).min(T::one()),
            hold_epochs: epochs_of(config.hold_s, epoch_s),
            timeout_epochs: epochs_of(config.pull_in_timeout_s, epoch_s),
            lock_threshold: config.lock_threshold,
            unlock_threshold: config.unlock_threshold,
            settle_threshold: config.settle_threshold,
        }
    }

    /// Back to pull-in (after re-initialization).
    pub(crate) fn restart(&mut self) {
        self.primed = false;
        self.status = LockStatus::PullIn;
        self.epochs = 0;
        self.above = 0;
    }

    /// The current verdict.
    pub fn status(&self) -> LockStatus {
        self.status
    }

    /// The smoothed alignment `η̄` (0 before the first epoch with satellites).
    pub fn alignment(&self) -> T {
        if self.aligned > T::zero() {
            self.coherent / self.aligned
        } else {
            T::zero()
        }
    }

    /// The settle statistic `s` of the last epoch (χ² scale; see the module documentation).
    pub fn settle_statistic(&self) -> T {
        self.settle_statistic
    }

    /// Feeds one epoch: the power sums (see [`super::EpochInformation`]), the normalized
    /// angle discriminator `v = J_αα⁻¹ u_α` (rad; zero for held angles) and `J_αα` (1/rad²).
    /// An epoch without satellites only advances the clock.
    pub(crate) fn update(
        &mut self,
        coherent_power: T,
        aligned_power: T,
        satellites: u8,
        normalized: &Vector3<T>,
        information: &Matrix3<T>,
    ) {
        self.epochs = self.epochs.saturating_add(1);
        let usable = satellites > 0
            && coherent_power.is_finite()
            && aligned_power.is_finite()
            && normalized.iter().all(|v| v.is_finite());
        if usable {
            let v = [normalized.x, normalized.y, normalized.z];
            if self.primed {
                self.coherent += (coherent_power - self.coherent) * self.gain;
                self.aligned += (aligned_power - self.aligned) * self.gain;
                for (s, &vi) in self.settle.iter_mut().zip(v.iter()) {
                    *s += (vi - *s) * self.gain;
                }
            } else {
                self.coherent = coherent_power;
                self.aligned = aligned_power;
                self.settle = v;
                self.primed = true;
            }
            // s = v̄ᵀ J v̄ · 2τ/T: the low-pass of gain g = T/τ leaves g/(2 − g) of the variance
            let vbar = Vector3::from(self.settle);
            let two = T::one() + T::one();
            let scale = (two - self.gain) / self.gain;
            let s = vbar.dot(&(information * vbar)) * scale;
            self.settle_statistic = if s.is_finite() {
                s
            } else {
                T::max_value().unwrap_or_else(T::one)
            };
        }
        let eta = self.alignment();
        let settled = self.settle_statistic <= self.settle_threshold;
        self.above = if self.primed && eta >= self.lock_threshold && settled {
            self.above.saturating_add(1)
        } else {
            0
        };
        let passed = self.above > self.hold_epochs;
        self.status = match self.status {
            LockStatus::PullIn if passed => LockStatus::Locked,
            LockStatus::PullIn if self.epochs > self.timeout_epochs => LockStatus::FalseLock,
            LockStatus::Locked if eta < self.unlock_threshold => LockStatus::FalseLock,
            LockStatus::FalseLock if passed => LockStatus::Locked,
            s => s,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn detector() -> LockDetector<f64> {
        LockDetector::new(&LockConfig::default(), 1e-3)
    }

    fn feed(d: &mut LockDetector<f64>, eta: f64, v: f64, epochs: usize) {
        let j = Matrix3::identity() * 1e5;
        for _ in 0..epochs {
            d.update(eta * 180.0, 180.0, 8, &Vector3::new(0.0, v, 0.0), &j);
        }
    }

    #[test]
    fn aligned_and_settled_locks_after_the_hold_time() {
        let mut d = detector();
        feed(&mut d, 1.0, 0.0, 100);
        assert_eq!(d.status(), LockStatus::PullIn);
        feed(&mut d, 1.0, 0.0, 2);
        assert_eq!(d.status(), LockStatus::Locked);
        // losing alignment flags it
        feed(&mut d, 0.7, 0.0, 100);
        assert_eq!(d.status(), LockStatus::FalseLock);
        // and only passing the test again clears the flag
        feed(&mut d, 1.0, 0.0, 300);
        assert_eq!(d.status(), LockStatus::Locked);
    }

    #[test]
    fn a_secondary_peak_or_an_unsettled_loop_is_flagged_after_the_timeout() {
        let mut d = detector();
        feed(&mut d, 0.72, 0.0, 1500); // the best secondary peak of G1
        assert_eq!(d.status(), LockStatus::PullIn);
        feed(&mut d, 0.72, 0.0, 2);
        assert_eq!(d.status(), LockStatus::FalseLock);
        // aligned but still sliding down the peak (v = 3e-3 rad, noise 3e-3 rad per epoch)
        let mut d = detector();
        feed(&mut d, 0.95, 3e-3, 1502);
        assert!(d.settle_statistic() > 16.27);
        assert_eq!(d.status(), LockStatus::FalseLock);
    }

    #[test]
    fn restart_returns_to_pull_in() {
        let mut d = detector();
        feed(&mut d, 0.5, 0.0, 2000);
        assert_eq!(d.status(), LockStatus::FalseLock);
        d.restart();
        assert_eq!(d.status(), LockStatus::PullIn);
        assert!(!LockConfig {
            unlock_threshold: 0.95,
            ..LockConfig::<f64>::default()
        }
        .is_valid());
    }
}
