//! GPS time: full week number and seconds of the week (f64: a time of week needs 1e-11
//! relative precision for a centimetre of range, far beyond f32).

use super::{HALF_WEEK_S, WEEK_S};

/// Error returned by [`GpsTime::new`] and [`GpsTime::add_seconds`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TimeError {
    /// The seconds were NaN or infinite.
    #[error("non-finite time")]
    NonFinite,
    /// The result would lie before week 0 or after week 65 535.
    #[error("time outside the representable weeks")]
    OutOfRange,
}

impl crate::error::Error for TimeError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::NonFinite => crate::error::ErrorKind::NonFinite,
            Self::OutOfRange => crate::error::ErrorKind::InvalidInput,
        }
    }
}

/// A GPS system time: full week number (not modulo 1024) and seconds of that week in
/// `[0, 604 800)`.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GpsTime {
    /// Full GPS week number (weeks since 1980-01-06).
    pub week: u16,
    /// Seconds of the week, `[0, 604 800)`, s.
    pub tow_s: f64,
}

impl GpsTime {
    /// The time `tow_s` seconds after the start of `week`; `tow_s` may lie outside one week
    /// (it is normalized into `[0, 604 800)` by moving whole weeks).
    ///
    /// # Errors
    /// [`TimeError::NonFinite`]; [`TimeError::OutOfRange`] when the normalized week does not
    /// fit a `u16`.
    pub fn new(week: u16, tow_s: f64) -> Result<Self, TimeError> {
        if !tow_s.is_finite() {
            return Err(TimeError::NonFinite);
        }
        let weeks = libm::floor(tow_s / WEEK_S);
        let full = f64::from(week) + weeks;
        if !(0.0..=f64::from(u16::MAX)).contains(&full) {
            return Err(TimeError::OutOfRange);
        }
        let mut tow = tow_s - weeks * WEEK_S;
        // rounding can leave tow == WEEK_S for a tow just below a week boundary
        let mut full = full as u16;
        if tow >= WEEK_S {
            tow -= WEEK_S;
            full = full.checked_add(1).ok_or(TimeError::OutOfRange)?;
        }
        Ok(Self {
            week: full,
            tow_s: tow.max(0.0),
        })
    }

    /// `self − other`, s (any number of weeks apart).
    pub fn seconds_since(&self, other: &Self) -> f64 {
        (f64::from(self.week) - f64::from(other.week)) * WEEK_S + (self.tow_s - other.tow_s)
    }

    /// The time `dt` seconds later (earlier for a negative `dt`).
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn add_seconds(&self, dt: f64) -> Result<Self, TimeError> {
        Self::new(self.week, self.tow_s + dt)
    }
}

/// `dt` wrapped into `[−302 400, 302 400]` s: IS-GPS-200's rule for `t − t_oe` and `t − t_oc`
/// (20.3.3.3.3.1), which makes an ephemeris usable across the week crossover when only
/// seconds of the week are known.
pub fn wrap_half_week(dt: f64) -> f64 {
    if dt > HALF_WEEK_S {
        dt - WEEK_S
    } else if dt < -HALF_WEEK_S {
        dt + WEEK_S
    } else {
        dt
    }
}

/// The full week number of a broadcast week `wn_mod` (modulo `modulus`: 1024 for the LNAV
/// week of subframe 1, 256 for the almanac and UTC weeks), chosen as the first week at or
/// after `earliest_week` with that residue.
pub fn resolve_week(wn_mod: u16, modulus: u16, earliest_week: u16) -> u16 {
    let m = u32::from(modulus.max(1));
    let base = u32::from(earliest_week);
    let residue = u32::from(wn_mod) % m;
    let offset = (residue + m - base % m) % m;
    let week = base + offset;
    u16::try_from(week).unwrap_or(u16::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_normalize_across_weeks() {
        let t = GpsTime::new(2195, 604_799.5).unwrap();
        let u = t.add_seconds(1.0).unwrap();
        assert_eq!(u.week, 2196);
        assert!((u.tow_s - 0.5).abs() < 1e-9);
        assert!((u.seconds_since(&t) - 1.0).abs() < 1e-9);
        let v = GpsTime::new(2196, -0.25).unwrap();
        assert_eq!(v.week, 2195);
        assert!((v.tow_s - 604_799.75).abs() < 1e-9);
        assert_eq!(GpsTime::new(0, -1.0), Err(TimeError::OutOfRange));
        assert_eq!(GpsTime::new(1, f64::NAN), Err(TimeError::NonFinite));
    }

    #[test]
    fn half_week_wrap_and_week_resolution() {
        assert_eq!(wrap_half_week(400_000.0), 400_000.0 - WEEK_S);
        assert_eq!(wrap_half_week(-400_000.0), -400_000.0 + WEEK_S);
        assert_eq!(wrap_half_week(100.0), 100.0);
        assert_eq!(resolve_week(147, 1024, 2048), 2195);
        assert_eq!(resolve_week(0, 1024, 2048), 2048);
        assert_eq!(resolve_week(1023, 1024, 2048), 3071);
        assert_eq!(resolve_week(147, 256, 2190), 2195);
    }
}
