//! Lock detectors and bit synchronization.

use super::cn0::WindowEstimate;

/// Code and phase lock decisions from window estimates, with hysteresis: the code lock is
/// declared after [`LockDetector::windows_to_declare`] good windows in a row, the phase lock
/// at the first good phase window with the code locked, and each is lost after
/// [`LockDetector::windows_to_lose`] bad ones. A window is good for the code when its C/N0
/// reaches the threshold *and* its correlation shape is a peak (early/late power at most
/// [`LockDetector::max_shape`] of the prompt's: a tone, a DC offset or a cross-correlation
/// plateau give a flat correlation); good for the phase when also its phase-lock indicator
/// reaches its threshold. A detector put on hold ([`LockDetector::hold`], a channel found to
/// sit on another satellite's cross-correlation) declares nothing until reset.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LockDetector {
    /// C/N0 below which the code is declared unlocked, dB-Hz.
    pub cn0_threshold_dbhz: f32,
    /// Phase-lock indicator (≈ cos 2Δφ) below which the phase is declared unlocked
    /// (0.5: |Δφ| > 30°).
    pub pld_threshold: f32,
    /// Largest correlation shape (early/late over prompt signal power) of a good window.
    pub max_shape: f32,
    /// Consecutive good windows before the code lock is declared.
    pub windows_to_declare: u8,
    /// Consecutive failing windows before a lock is declared lost.
    pub windows_to_lose: u8,
    code_lock: bool,
    phase_lock: bool,
    good_code: u8,
    good_phase: u8,
    bad_code: u8,
    bad_phase: u8,
    held: bool,
}

/// The thresholds of a [`LockDetector`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LockThresholds {
    /// C/N0 threshold of the code lock, dB-Hz.
    pub cn0_dbhz: f32,
    /// Phase-lock indicator threshold.
    pub pld: f32,
    /// Largest correlation shape of a good window.
    pub max_shape: f32,
    /// Good windows in a row that declare a lock.
    pub windows_to_declare: u8,
    /// Bad windows in a row that lose it.
    pub windows_to_lose: u8,
}

impl LockDetector {
    /// A detector with the given thresholds, unlocked.
    pub fn new(t: &LockThresholds) -> Self {
        Self {
            cn0_threshold_dbhz: t.cn0_dbhz,
            pld_threshold: t.pld,
            max_shape: t.max_shape,
            windows_to_declare: t.windows_to_declare,
            windows_to_lose: t.windows_to_lose,
            code_lock: false,
            phase_lock: false,
            good_code: 0,
            good_phase: 0,
            bad_code: 0,
            bad_phase: 0,
            held: false,
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

    /// Whether the detector is on hold.
    pub fn held(&self) -> bool {
        self.held
    }

    /// Updates with one window's estimate. The phase lock needs the code lock declared
    /// (so both are declared only after the code's good windows) and one good phase window.
    pub fn update(&mut self, e: &WindowEstimate) {
        let code_ok = e.cn0_dbhz >= self.cn0_threshold_dbhz && e.shape <= self.max_shape;
        let (declare, lose) = (self.windows_to_declare, self.windows_to_lose);
        let held = self.held;
        step(
            &mut self.code_lock,
            (&mut self.good_code, &mut self.bad_code),
            code_ok,
            (declare, lose),
            held,
        );
        let phase_ok = code_ok && self.code_lock && e.phase_lock_indicator >= self.pld_threshold;
        step(
            &mut self.phase_lock,
            (&mut self.good_phase, &mut self.bad_phase),
            phase_ok,
            (1, lose),
            held,
        );
    }

    /// Declares both locks lost and keeps them so until [`LockDetector::reset`].
    pub fn hold(&mut self) {
        self.reset();
        self.held = true;
    }

    /// Declares both locks lost (and lifts a hold).
    pub fn reset(&mut self) {
        *self = Self::new(&LockThresholds {
            cn0_dbhz: self.cn0_threshold_dbhz,
            pld: self.pld_threshold,
            max_shape: self.max_shape,
            windows_to_declare: self.windows_to_declare,
            windows_to_lose: self.windows_to_lose,
        });
    }
}

fn step(lock: &mut bool, counts: (&mut u8, &mut u8), ok: bool, limits: (u8, u8), held: bool) {
    let (good, bad) = counts;
    if held {
        *lock = false;
        return;
    }
    if ok {
        *good = good.saturating_add(1);
        *bad = 0;
        if *good >= limits.0.max(1) {
            *lock = true;
        }
    } else {
        *bad = bad.saturating_add(1);
        *good = 0;
        if *bad >= limits.1.max(1) {
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
                if u32::from(best) * 2 >= u32::from(self.transitions)
                    && u32::from(best) >= 4 * u32::from(second)
                {
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
