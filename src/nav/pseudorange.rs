//! Times of transmission and pseudoranges.
//!
//! A tracking channel knows, at any instant it measures (a receiver sample), which part of the
//! satellite's signal it is receiving: the subframe it decoded last (its start time from the
//! HOW), the data bits and code periods since that subframe started, and the replica's code
//! phase. That is the satellite-clock time of transmission
//!
//! ```text
//! t_sv = TOW(subframe start) + bits × 20 ms + code periods × 1 ms + code phase / 1.023 MHz
//! ```
//!
//! and the pseudorange is `ρ = c (t_rx − t_sv)` with `t_rx` the receiver clock's reading at the
//! same instant.
//!
//! # What a tracking channel must provide ([`TransmitTime`])
//!
//! * the PRN;
//! * the GPS week and time of week of the start of a subframe it decoded (from
//!   [`super::decoder::ChannelDecoder::anchor`]: the subframe's HOW, the week from the
//!   [`super::store::NavigationStore`]);
//! * the count of code periods since that subframe's first bit started, split into whole bits
//!   (20 code periods) and the remaining code periods (0–19): the channel's code-period index
//!   of the measurement minus the index at which the subframe started;
//! * the replica's code phase at the measurement instant, chips in `[0, 1023)` (for the
//!   crate's channels: `EpochCorrelations::code_phase_at_first` at the epoch's first sample,
//!   in 2⁻³² chip, plus the code advanced between that sample and the measurement instant).
//!
//! Precision: times and ranges are `f64` (a time of week of 6·10⁵ s resolves 1.2·10⁻¹⁰ s,
//! 3.5 cm); the code phase is `f32` (1023 chips resolve 6·10⁻⁵ chip, 1.8 cm).

use super::bits::EPOCHS_PER_BIT;
use super::time::{GpsTime, TimeError};
use super::{SPEED_OF_LIGHT, WEEK_S};
use crate::signal::ca_code::CA_CHIP_RATE_HZ;

/// Chips per C/A code period.
pub const CODE_CHIPS: f32 = 1023.0;
/// Seconds per C/A code period.
pub const CODE_PERIOD_S: f64 = 1e-3;
/// Seconds per LNAV data bit.
pub const BIT_S: f64 = 0.02;
/// Shortest signal flight accepted, s (a receiver on the satellite's side of the Earth).
pub const MIN_FLIGHT_S: f64 = 0.0;
/// Longest signal flight accepted, s (the farthest GPS satellite from a LEO receiver is at
/// about 0.1 s; the margin covers a receiver clock set from a TOW to within 0.1 s).
pub const MAX_FLIGHT_S: f64 = 0.3;

/// Error returned by [`TransmitTime::new`], [`TransmitTime::gps_time`] and [`pseudorange_m`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TransmitTimeError {
    /// The code phase or the receive time was not finite.
    #[error("non-finite code phase or time")]
    NonFinite,
    /// The subframe's time of week is not a multiple of 6 s below a week.
    #[error("subframe time of week invalid")]
    SubframeTow,
    /// Code periods not in 0–19 or code phase not in `[0, 1023)` chips.
    #[error("code period count or code phase out of range")]
    CodeOutOfRange,
    /// The pseudorange's signal flight is outside [`MIN_FLIGHT_S`]..[`MAX_FLIGHT_S`]: the
    /// receiver clock is not set or the channel's count is wrong.
    #[error("signal flight time implausible")]
    Flight,
    /// The time lies outside the representable weeks.
    #[error("time out of range")]
    Time(#[from] TimeError),
}

impl crate::error::Error for TransmitTimeError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::NonFinite => crate::error::ErrorKind::NonFinite,
            Self::Time(e) => crate::error::Error::kind(e),
            _ => crate::error::ErrorKind::InvalidInput,
        }
    }
}

/// A satellite-clock time of transmission, as a tracking channel counts it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TransmitTime {
    /// Satellite PRN.
    pub prn: u8,
    /// Full GPS week of the subframe start.
    pub week: u16,
    /// Time of week of the start of the decoded subframe the count starts from, s
    /// (a multiple of 6).
    pub subframe_tow_s: u32,
    /// Whole data bits since that subframe's start.
    pub bits: u32,
    /// Whole code periods since the current bit's start, 0–19.
    pub code_periods: u8,
    /// Code phase of the replica at the measurement instant, chips, `[0, 1023)`.
    pub code_phase_chips: f32,
}

impl TransmitTime {
    /// A checked time of transmission.
    ///
    /// # Errors
    /// [`TransmitTimeError::SubframeTow`], [`TransmitTimeError::CodeOutOfRange`],
    /// [`TransmitTimeError::NonFinite`].
    pub fn new(
        prn: u8,
        week: u16,
        subframe_tow_s: u32,
        bits: u32,
        code_periods: u8,
        code_phase_chips: f32,
    ) -> Result<Self, TransmitTimeError> {
        if !code_phase_chips.is_finite() {
            return Err(TransmitTimeError::NonFinite);
        }
        if subframe_tow_s % 6 != 0 || f64::from(subframe_tow_s) >= WEEK_S {
            return Err(TransmitTimeError::SubframeTow);
        }
        if u64::from(code_periods) >= EPOCHS_PER_BIT
            || !(0.0..CODE_CHIPS).contains(&code_phase_chips)
        {
            return Err(TransmitTimeError::CodeOutOfRange);
        }
        Ok(Self {
            prn,
            week,
            subframe_tow_s,
            bits,
            code_periods,
            code_phase_chips,
        })
    }

    /// Seconds since the subframe's start: bits × 20 ms + code periods × 1 ms + code phase /
    /// chip rate (small, exact to 10⁻¹⁴ s).
    pub fn since_subframe_s(&self) -> f64 {
        f64::from(self.bits) * BIT_S
            + f64::from(self.code_periods) * CODE_PERIOD_S
            + f64::from(self.code_phase_chips) / CA_CHIP_RATE_HZ
    }

    /// The time of transmission on the satellite's clock.
    ///
    /// # Errors
    /// [`TransmitTimeError::Time`] when it lies outside the representable weeks.
    pub fn gps_time(&self) -> Result<GpsTime, TransmitTimeError> {
        Ok(GpsTime::new(
            self.week,
            f64::from(self.subframe_tow_s) + self.since_subframe_s(),
        )?)
    }
}

/// The pseudorange `c (t_rx − t_sv)` of a signal transmitted at `transmit` and received at
/// the receiver-clock time `receive`, m. The subtraction of the large times is done first
/// (exact in f64), then the small parts.
///
/// # Errors
/// [`TransmitTimeError::NonFinite`]; [`TransmitTimeError::Flight`] for a flight time outside
/// [`MIN_FLIGHT_S`]..[`MAX_FLIGHT_S`].
pub fn pseudorange_m(receive: &GpsTime, transmit: &TransmitTime) -> Result<f64, TransmitTimeError> {
    if !receive.tow_s.is_finite() {
        return Err(TransmitTimeError::NonFinite);
    }
    let weeks = f64::from(receive.week) - f64::from(transmit.week);
    let coarse = weeks * WEEK_S + (receive.tow_s - f64::from(transmit.subframe_tow_s));
    let flight = coarse - transmit.since_subframe_s();
    if !(MIN_FLIGHT_S..=MAX_FLIGHT_S).contains(&flight) {
        return Err(TransmitTimeError::Flight);
    }
    Ok(flight * SPEED_OF_LIGHT)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transmit_time_adds_bits_code_periods_and_chips() {
        let t = TransmitTime::new(5, 2195, 233_466, 151, 7, 511.5).unwrap();
        let expected = 233_466.0 + 151.0 * 0.02 + 7e-3 + 511.5 / 1.023e6;
        let g = t.gps_time().unwrap();
        assert_eq!(g.week, 2195);
        assert!((g.tow_s - expected).abs() < 1e-9);
        let rx = GpsTime::new(2195, expected + 0.072).unwrap();
        let pr = pseudorange_m(&rx, &t).unwrap();
        assert!((pr - 0.072 * SPEED_OF_LIGHT).abs() < 0.05, "{pr}");
    }

    #[test]
    fn the_week_crossover_and_bad_counts_are_handled() {
        // subframe started 6 s before the week's end, received in the next week
        let t = TransmitTime::new(1, 2195, 604_794, 299, 19, 1000.0).unwrap();
        let tx = t.gps_time().unwrap();
        assert_eq!(tx.week, 2195);
        let rx = tx.add_seconds(0.07).unwrap();
        assert_eq!(rx.week, 2196);
        let pr = pseudorange_m(&rx, &t).unwrap();
        assert!((pr - 0.07 * SPEED_OF_LIGHT).abs() < 0.05);
        assert_eq!(
            TransmitTime::new(1, 2195, 604_795, 0, 0, 0.0),
            Err(TransmitTimeError::SubframeTow)
        );
        assert_eq!(
            TransmitTime::new(1, 2195, 6, 0, 20, 0.0),
            Err(TransmitTimeError::CodeOutOfRange)
        );
        assert_eq!(
            TransmitTime::new(1, 2195, 6, 0, 0, 1023.0),
            Err(TransmitTimeError::CodeOutOfRange)
        );
        assert_eq!(
            TransmitTime::new(1, 2195, 6, 0, 0, f32::NAN),
            Err(TransmitTimeError::NonFinite)
        );
        let late = GpsTime::new(2195, 7.0).unwrap();
        let t = TransmitTime::new(1, 2195, 6, 0, 0, 0.0).unwrap();
        assert_eq!(pseudorange_m(&late, &t), Err(TransmitTimeError::Flight));
    }
}
