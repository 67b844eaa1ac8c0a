//! Per-antenna signal power: an antenna whose signal vanishes (blocked by a structure, a
//! failed LNA, a cable) is left out of every stage until it returns.
//!
//! Each epoch the signal power of every antenna is estimated from the prompts of all tracked
//! satellites, `Σ_i (|z_P,i|² − 2)` in noise units (the `−2` removes the noise), and smoothed
//! with gain 1/16 (a 16 ms time constant). An antenna below `ratio` times the strongest is
//! blocked; a blocked antenna is restored above `2 · ratio` times it (hysteresis).

/// Smoothing gain of the power estimates.
const GAIN: f32 = 1.0 / 16.0;

/// The monitor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct AntennaMonitor {
    power: [f32; 3],
    primed: bool,
    blocked: [bool; 3],
}

impl AntennaMonitor {
    /// Takes one epoch's power sums; returns the antennas whose state changed, with the new
    /// state (true = blocked).
    pub fn update(&mut self, powers: &[f32; 3], ratio: f32) -> heapless::Vec<(usize, bool), 3> {
        let mut changes = heapless::Vec::new();
        if !powers.iter().all(|p| p.is_finite()) {
            return changes;
        }
        if self.primed {
            for (s, p) in self.power.iter_mut().zip(powers.iter()) {
                *s += (*p - *s) * GAIN;
            }
        } else {
            self.power = *powers;
            self.primed = true;
        }
        let strongest = self.power.iter().fold(0.0f32, |a, &b| a.max(b));
        if !(strongest > 0.0) {
            return changes;
        }
        // (indices from `0..3`, not `enumerate`: its counter keeps an overflow check)
        for (i, (p, b)) in (0..3).zip(self.power.iter().zip(self.blocked.iter_mut())) {
            let next = if *b {
                *p < 2.0 * ratio * strongest
            } else {
                *p < ratio * strongest
            };
            if next != *b {
                *b = next;
                // one entry per antenna: the vector holds them all
                if changes.push((i, next)).is_err() {
                    break;
                }
            }
        }
        changes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_silent_antenna_is_blocked_within_a_few_time_constants_and_restored() {
        let mut m = AntennaMonitor::default();
        for _ in 0..100 {
            assert!(m.update(&[300.0, 310.0, 290.0], 0.2).is_empty());
        }
        let mut blocked_after = None;
        for k in 0..100 {
            let c = m.update(&[300.0, 2.0, 290.0], 0.2);
            if c.iter().any(|&(a, b)| a == 1 && b) {
                blocked_after = Some(k);
                break;
            }
        }
        assert!(blocked_after.is_some_and(|k| k < 40), "{blocked_after:?}");
        let mut restored_after = None;
        for k in 0..100 {
            let c = m.update(&[300.0, 305.0, 290.0], 0.2);
            if c.iter().any(|&(a, b)| a == 1 && !b) {
                restored_after = Some(k);
                break;
            }
        }
        assert!(restored_after.is_some_and(|k| k < 40), "{restored_after:?}");
    }
}
