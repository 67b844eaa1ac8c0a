//! The navigation decoder of one tracking channel: 1 ms prompts → bit synchronization → bits →
//! subframe synchronization → subframes, and the time anchor (the start of the latest decoded
//! subframe on the channel's code-period count) that turns the channel's count into a
//! [`TransmitTime`].

use super::bits::{BitDecoder, BitError, BitSyncConfig, EPOCHS_PER_BIT};
use super::pseudorange::{TransmitTime, TransmitTimeError};
use super::subframe::{Subframe, SubframeError, SubframeSync};

/// Error returned by [`ChannelDecoder::push_prompt`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DecodeError {
    /// The bit stage refused the prompt or found a gap (after a gap the subframe stage
    /// starts over).
    #[error("bit stage")]
    Bit(#[from] BitError),
    /// The subframe stage refused a subframe (parity).
    #[error("subframe stage")]
    Subframe(#[from] SubframeError),
}

impl crate::error::Error for DecodeError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::Bit(e) => crate::error::Error::kind(e),
            Self::Subframe(e) => crate::error::Error::kind(e),
        }
    }
}

/// Error returned by [`ChannelDecoder::transmit_time`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AnchorError {
    /// No subframe decoded yet, or its week is unknown.
    #[error("no time anchor yet")]
    NoAnchor,
    /// The epoch lies before the anchor.
    #[error("epoch before the anchor")]
    BeforeAnchor,
    /// The resulting time of transmission was refused.
    #[error("time of transmission refused")]
    Transmit(#[from] TransmitTimeError),
}

impl crate::error::Error for AnchorError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::Transmit(e) => crate::error::Error::kind(e),
            _ => crate::error::ErrorKind::InvalidInput,
        }
    }
}

/// The start of a decoded subframe on the channel's code-period count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimeAnchor {
    /// Channel epoch (code period) at which the subframe's first bit started.
    pub start_epoch: u64,
    /// Time of week of that instant, s (satellite clock).
    pub tow_s: u32,
    /// Full GPS week, once known (from [`ChannelDecoder::set_week`]).
    pub week: Option<u16>,
}

/// One channel's navigation decoder.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelDecoder {
    prn: u8,
    bits: BitDecoder,
    frames: SubframeSync,
    anchor: Option<TimeAnchor>,
    parity_failures: u32,
    gaps: u32,
}

impl ChannelDecoder {
    /// A decoder for satellite `prn`.
    pub fn new(prn: u8, config: BitSyncConfig) -> Self {
        Self {
            prn,
            bits: BitDecoder::new(config),
            frames: SubframeSync::new(),
            anchor: None,
            parity_failures: 0,
            gaps: 0,
        }
    }

    /// The satellite.
    pub fn prn(&self) -> u8 {
        self.prn
    }

    /// Bit edge phase (`epoch % 20`), once synchronized.
    pub fn bit_edge(&self) -> Option<u8> {
        self.bits.edge()
    }

    /// Whether subframes are being decoded (the last one passed and the next is expected).
    pub fn subframe_synchronized(&self) -> bool {
        self.frames.synchronized()
    }

    /// Subframes this decoder refused for their parity.
    pub fn parity_failures(&self) -> u32 {
        self.parity_failures
    }

    /// Breaks in the bit stream (missing epochs inside a bit).
    pub fn gaps(&self) -> u32 {
        self.gaps
    }

    /// Takes the prompt I (any unit, reference antenna) of channel epoch `epoch`; returns a
    /// subframe when one completed. The anchor moves to every decoded subframe.
    ///
    /// # Errors
    /// [`DecodeError::Bit`] (a gap restarts the subframe search), [`DecodeError::Subframe`]
    /// (a parity failure, counted).
    pub fn push_prompt(
        &mut self,
        epoch: u64,
        prompt_i: f32,
    ) -> Result<Option<Subframe>, DecodeError> {
        let bit = match self.bits.push(epoch, prompt_i) {
            Ok(Some(bit)) => bit,
            Ok(None) => return Ok(None),
            Err(BitError::Gap) => {
                self.gaps = self.gaps.saturating_add(1);
                self.frames.reset();
                return Err(BitError::Gap.into());
            }
            Err(e) => return Err(e.into()),
        };
        match self.frames.push(&bit) {
            Ok(Some(subframe)) => {
                self.move_anchor(&subframe);
                Ok(Some(subframe))
            }
            Ok(None) => Ok(None),
            Err(e) => {
                if matches!(e, SubframeError::Parity { .. } | SubframeError::Preamble) {
                    self.parity_failures = self.parity_failures.saturating_add(1);
                }
                Err(e.into())
            }
        }
    }

    fn move_anchor(&mut self, subframe: &Subframe) {
        let tow_s = subframe.start_tow_s();
        // the week advances when the time of week wraps
        let week = self.anchor.and_then(|a| {
            let w = a.week?;
            if tow_s < a.tow_s {
                w.checked_add(1)
            } else {
                Some(w)
            }
        });
        self.anchor = Some(TimeAnchor {
            start_epoch: subframe.start_epoch,
            tow_s,
            week,
        });
    }

    /// Sets the full GPS week of the current anchor (from the store's subframe 1); later
    /// anchors follow it across the week crossover.
    pub fn set_week(&mut self, week: u16) {
        if let Some(a) = self.anchor.as_mut() {
            a.week = Some(week);
        }
    }

    /// The latest anchor.
    pub fn anchor(&self) -> Option<TimeAnchor> {
        self.anchor
    }

    /// The time of transmission at channel epoch `epoch` (the code period whose start the
    /// replica's code phase counts from) and code phase `code_phase_chips`.
    ///
    /// # Errors
    /// [`AnchorError::NoAnchor`] before the first subframe or while the week is unknown,
    /// [`AnchorError::BeforeAnchor`], [`AnchorError::Transmit`].
    pub fn transmit_time(
        &self,
        epoch: u64,
        code_phase_chips: f32,
    ) -> Result<TransmitTime, AnchorError> {
        let anchor = self.anchor.ok_or(AnchorError::NoAnchor)?;
        let week = anchor.week.ok_or(AnchorError::NoAnchor)?;
        let periods = epoch
            .checked_sub(anchor.start_epoch)
            .ok_or(AnchorError::BeforeAnchor)?;
        let bits = u32::try_from(periods / EPOCHS_PER_BIT).unwrap_or(u32::MAX);
        let rest = (periods % EPOCHS_PER_BIT) as u8;
        Ok(TransmitTime::new(
            self.prn,
            week,
            anchor.tow_s,
            bits,
            rest,
            code_phase_chips,
        )?)
    }

    /// Forgets the bit and subframe synchronization and the anchor (after a loss of lock);
    /// the counters stay.
    pub fn reset(&mut self) {
        self.bits.reset();
        self.frames.reset();
        self.anchor = None;
    }
}
