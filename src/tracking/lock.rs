//! Lock detectors and bit synchronization.

/// Code and phase lock decisions from window estimates, with hysteresis.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LockDetector {
    /// C/N0 below which the code is declared unlocked, dB-Hz.
    pub cn0_threshold_dbhz: f32,
    /// Phase-lock indicator (≈ cos 2Δφ) below which the phase is declared unlocked
    /// (0.5: |Δφ| > 30°).
    pub pld_threshold: f32,
    /// Consecutive failing windows before a lock is declared lost.
    pub windows_to_lose: u8,
    code_lock: bool,
    phase_lock: bool,
    bad_code: u8,
    bad_phase: u8,
}

impl LockDetector {
    /// A detector with the given thresholds, unlocked.
    pub fn new(cn0_threshold_dbhz: f32, pld_threshold: f32, windows_to_lose: u8) -> Self {
        Self {
            cn0_threshold_dbhz,
            pld_threshold,
            windows_to_lose,
            code_lock: false,
            phase_lock: false,
            bad_code: 0,
            bad_phase: 0,
        }
    }

    /// Code lock (signal present and the DLL on it).
    pub fn code_lock(&self) -> bool {
        self.code_lock
    }

    /// Phase lock (the Costas PLL on the carrier, modulo the data-bit half cycle).
    pub fn phase_lock(&self) -> bool {
        self.phase_lock
    }

    /// Updates with one window's C/N0 and phase-lock indicator. Locks are declared at the
    /// first good window and lost after `windows_to_lose` bad ones in a row.
    pub fn update(&mut self, cn0_dbhz: f32, pld: f32) {
        let code_ok = cn0_dbhz >= self.cn0_threshold_dbhz;
        let phase_ok = code_ok && pld >= self.pld_threshold;
        step(
            &mut self.code_lock,
            &mut self.bad_code,
            code_ok,
            self.windows_to_lose,
        );
        step(
            &mut self.phase_lock,
            &mut self.bad_phase,
            phase_ok,
            self.windows_to_lose,
        );
    }

    /// Declares both locks lost.
    pub fn reset(&mut self) {
        *self = Self::new(
            self.cn0_threshold_dbhz,
            self.pld_threshold,
            self.windows_to_lose,
        );
    }
}

fn step(lock: &mut bool, bad: &mut u8, ok: bool, limit: u8) {
    if ok {
        *lock = true;
        *bad = 0;
    } else {
        *bad = bad.saturating_add(1);
        if *bad >= limit.max(1) {
            *lock = false;
        }
    }
}

/// Bit synchronization by the histogram of prompt-I sign changes over the 20 epoch positions
/// of a 20 ms data bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitSync {
    histogram: [u16; 20],
    last_sign: i8,
    transitions: u16,
    edge: Option<u8>,
}

impl BitSync {
    /// Transitions needed before a decision.
    pub const MIN_TRANSITIONS: u16 = 40;

    /// Epoch position (0–19, counted as `epoch % 20`) at which bits start, once synchronized.
    pub fn edge(&self) -> Option<u8> {
        self.edge
    }

    /// Adds epoch `epoch`'s prompt I. Declares synchronization when at least
    /// [`BitSync::MIN_TRANSITIONS`] sign changes were seen and one position holds at least
    /// half of them and four times the runner-up.
    pub fn add(&mut self, epoch: u32, prompt_i: i32) {
        let sign = if prompt_i >= 0 { 1 } else { -1 };
        if self.last_sign != 0 && sign != self.last_sign && self.edge.is_none() {
            let slot = (epoch % 20) as usize;
            if let Some(h) = self.histogram.get_mut(slot) {
                *h = h.saturating_add(1);
            }
            self.transitions = self.transitions.saturating_add(1);
            if self.transitions >= Self::MIN_TRANSITIONS {
                let (mut best, mut at, mut second) = (0u16, 0usize, 0u16);
                for (k, &h) in self.histogram.iter().enumerate() {
                    if h > best {
                        second = best;
                        best = h;
                        at = k;
                    } else if h > second {
                        second = h;
                    }
                }
                if u32::from(best) * 2 >= u32::from(self.transitions) && best >= 4 * second {
                    self.edge = Some(at as u8);
                }
            }
        }
        self.last_sign = sign;
    }

    /// Forgets everything.
    pub fn reset(&mut self) {
        *self = Self::default();
    }
}
