//! The navigation data of the whole constellation, built from decoded subframes: the newest
//! consistent, plausible ephemeris per PRN (fixed capacity for PRN 1–32), the almanac, the
//! ionosphere and UTC parameters, and counters of what was refused.
//!
//! Subframes 1, 2 and 3 are kept per PRN as they arrive, from any frame: as soon as the three
//! held agree (IODE of subframes 2 and 3 equal to the low eight bits of the IODC), they form an
//! [`Ephemeris`], which is checked ([`Ephemeris::check`]) and replaces the stored one unless
//! it is older. Combining subframes of consecutive frames of the same issue gets a first
//! ephemeris in 18 s after the first subframe 1, 2 or 3 instead of up to 30 s + 18 s.

use super::ephemeris::{Ephemeris, EphemerisError, PlausibilityLimits};
use super::message::{
    decode, AlmanacData, AlmanacReference, ClockData, KlobucharParameters, NavMessage, OrbitData2,
    OrbitData3, UtcParameters,
};
use super::subframe::{Subframe, SubframeError};
use super::time::{resolve_week, wrap_half_week};

/// Number of GPS PRNs the store holds (1–32).
pub const GPS_PRNS: usize = 32;

/// Configuration of a [`NavigationStore`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StoreConfig {
    /// The earliest full GPS week the receiver can be in: resolves the 10-bit week of
    /// subframe 1 (default 2048, the April 2019 rollover: valid until 2038).
    pub earliest_week: u16,
    /// Plausibility limits an ephemeris must meet.
    pub limits: PlausibilityLimits,
}

impl Default for StoreConfig {
    fn default() -> Self {
        Self {
            earliest_week: 2048,
            limits: PlausibilityLimits::default(),
        }
    }
}

/// What the store counted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StoreCounters {
    /// Subframes accepted.
    pub subframes: u32,
    /// Subframes refused by their parity or a missing preamble at the expected start
    /// ([`NavigationStore::record_decode_error`]).
    pub parity_failures: u32,
    /// Consistent ephemeris sets refused as implausible.
    pub implausible: u32,
    /// New ephemerides stored.
    pub ephemerides: u32,
    /// Consistent sets older than the stored one, ignored.
    pub older_ignored: u32,
}

/// What one subframe changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreUpdate {
    /// A new ephemeris of this PRN is stored.
    Ephemeris {
        /// The satellite.
        prn: u8,
        /// Its issue of data.
        iode: u8,
    },
    /// Held, waiting for the other subframes of the same issue (or the same set again).
    Pending,
    /// An almanac entry was stored.
    Almanac {
        /// The satellite the almanac describes.
        prn: u8,
    },
    /// The almanac reference (subframe 5 page 25) was stored.
    AlmanacReference,
    /// Ionosphere and UTC parameters were stored.
    IonosphereUtc,
    /// A page the store does not keep.
    Ignored,
}

/// Error returned by [`NavigationStore::add_subframe`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StoreError {
    /// The PRN is not 1–32.
    #[error("prn {prn} outside 1-32")]
    InvalidPrn {
        /// The PRN given.
        prn: u8,
    },
    /// A consistent set was refused (counted in [`StoreCounters::implausible`]); the stored
    /// ephemeris is unchanged.
    #[error("ephemeris of prn {prn} refused")]
    Implausible {
        /// The satellite.
        prn: u8,
        /// Why.
        #[source]
        source: EphemerisError,
    },
}

impl crate::error::Error for StoreError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::InvalidPrn { .. } => crate::error::ErrorKind::InvalidInput,
            Self::Implausible { source, .. } => crate::error::Error::kind(source),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct PrnSlot {
    clock: Option<(ClockData, u16)>,
    orbit2: Option<OrbitData2>,
    orbit3: Option<OrbitData3>,
    current: Option<Ephemeris>,
}

/// The navigation data store.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NavigationStore {
    config: StoreConfig,
    slots: [PrnSlot; GPS_PRNS],
    almanac: [Option<AlmanacData>; GPS_PRNS],
    almanac_reference: Option<AlmanacReference>,
    ionosphere: Option<KlobucharParameters>,
    utc: Option<UtcParameters>,
    week: Option<u16>,
    counters: StoreCounters,
}

impl NavigationStore {
    /// An empty store.
    pub fn new(config: StoreConfig) -> Self {
        Self {
            config,
            slots: [PrnSlot::default(); GPS_PRNS],
            almanac: [None; GPS_PRNS],
            almanac_reference: None,
            ionosphere: None,
            utc: None,
            week: None,
            counters: StoreCounters::default(),
        }
    }

    /// Adds a subframe decoded from satellite `prn`.
    ///
    /// # Errors
    /// [`StoreError::InvalidPrn`]; [`StoreError::Implausible`] when the subframe completed a
    /// consistent set that fails the plausibility checks.
    pub fn add_subframe(
        &mut self,
        prn: u8,
        subframe: &Subframe,
    ) -> Result<StoreUpdate, StoreError> {
        let index = usize::from(prn)
            .checked_sub(1)
            .filter(|&i| i < GPS_PRNS)
            .ok_or(StoreError::InvalidPrn { prn })?;
        self.counters.subframes = self.counters.subframes.saturating_add(1);
        let message = decode(subframe);
        let earliest = self.config.earliest_week;
        let Some(slot) = self.slots.get_mut(index) else {
            return Err(StoreError::InvalidPrn { prn });
        };
        match message {
            NavMessage::Clock(c) => {
                let week = resolve_week(c.week_mod_1024, 1024, earliest);
                self.week = Some(self.week.map_or(week, |w| w.max(week)));
                slot.clock = Some((c, week));
            }
            NavMessage::Orbit2(o) => slot.orbit2 = Some(o),
            NavMessage::Orbit3(o) => slot.orbit3 = Some(o),
            NavMessage::Almanac(a) => return Ok(self.store_almanac(a)),
            NavMessage::AlmanacReference(r) => {
                self.almanac_reference = Some(r);
                return Ok(StoreUpdate::AlmanacReference);
            }
            NavMessage::IonosphereUtc(iono, utc) => {
                self.ionosphere = Some(iono);
                self.utc = Some(utc);
                return Ok(StoreUpdate::IonosphereUtc);
            }
            NavMessage::Other { .. } => return Ok(StoreUpdate::Ignored),
        }
        self.assemble(index, prn)
    }

    fn store_almanac(&mut self, a: AlmanacData) -> StoreUpdate {
        let slot = usize::from(a.prn)
            .checked_sub(1)
            .and_then(|i| self.almanac.get_mut(i));
        match slot {
            Some(s) => {
                *s = Some(a);
                StoreUpdate::Almanac { prn: a.prn }
            }
            None => StoreUpdate::Ignored,
        }
    }

    /// Forms the ephemeris of slot `index` when its three subframes agree.
    fn assemble(&mut self, index: usize, prn: u8) -> Result<StoreUpdate, StoreError> {
        let limits = self.config.limits;
        let Some(slot) = self.slots.get_mut(index) else {
            return Err(StoreError::InvalidPrn { prn });
        };
        let (Some((clock, week)), Some(o2), Some(o3)) = (slot.clock, slot.orbit2, slot.orbit3)
        else {
            return Ok(StoreUpdate::Pending);
        };
        let Some(eph) = Ephemeris::from_subframes(prn, week, &clock, &o2, &o3) else {
            return Ok(StoreUpdate::Pending);
        };
        if let Some(cur) = slot.current {
            if cur.iode == eph.iode && cur.iodc == eph.iodc && cur.toe_s == eph.toe_s {
                return Ok(StoreUpdate::Pending);
            }
            let age = wrap_half_week(eph.toe().seconds_since(&cur.toe()));
            if age < 0.0 {
                self.counters.older_ignored = self.counters.older_ignored.saturating_add(1);
                return Ok(StoreUpdate::Pending);
            }
        }
        if let Err(source) = eph.check(&limits) {
            self.counters.implausible = self.counters.implausible.saturating_add(1);
            warn!("ephemeris refused, prn {}", prn);
            return Err(StoreError::Implausible { prn, source });
        }
        slot.current = Some(eph);
        self.counters.ephemerides = self.counters.ephemerides.saturating_add(1);
        info!("ephemeris stored, prn {} iode {}", prn, eph.iode);
        Ok(StoreUpdate::Ephemeris {
            prn,
            iode: eph.iode,
        })
    }

    /// Counts a subframe refused by the synchronizer (a parity failure, or no preamble where
    /// the next subframe had to start); other errors are not counted.
    pub fn record_decode_error(&mut self, error: &SubframeError) {
        if matches!(
            error,
            SubframeError::Parity { .. } | SubframeError::Preamble
        ) {
            self.counters.parity_failures = self.counters.parity_failures.saturating_add(1);
        }
    }

    /// The stored ephemeris of `prn`.
    pub fn ephemeris(&self, prn: u8) -> Option<&Ephemeris> {
        let i = usize::from(prn).checked_sub(1)?;
        self.slots.get(i)?.current.as_ref()
    }

    /// Every stored ephemeris, by PRN.
    pub fn ephemerides(&self) -> impl Iterator<Item = &Ephemeris> {
        self.slots.iter().filter_map(|s| s.current.as_ref())
    }

    /// The almanac of `prn`, if a page of it was decoded.
    pub fn almanac(&self, prn: u8) -> Option<&AlmanacData> {
        let i = usize::from(prn).checked_sub(1)?;
        self.almanac.get(i)?.as_ref()
    }

    /// Subframe 5 page 25, if decoded.
    pub fn almanac_reference(&self) -> Option<&AlmanacReference> {
        self.almanac_reference.as_ref()
    }

    /// The broadcast ionosphere parameters, if decoded.
    pub fn ionosphere(&self) -> Option<KlobucharParameters> {
        self.ionosphere
    }

    /// The GPS–UTC parameters, if decoded.
    pub fn utc(&self) -> Option<UtcParameters> {
        self.utc
    }

    /// The latest full GPS week decoded from any subframe 1.
    pub fn week(&self) -> Option<u16> {
        self.week
    }

    /// The counters.
    pub fn counters(&self) -> StoreCounters {
        self.counters
    }
}

impl Default for NavigationStore {
    fn default() -> Self {
        Self::new(StoreConfig::default())
    }
}
