//! An embedded-hal 1.0 SPI driver for the `NTLab` NT1065 four-channel GNSS front end.
//!
//! The NT1065 has four RF channels fed from one or two on-chip synthesizers (PLL A, PLL B).
//! With every channel on PLL A, all four down-conversions share one LO and one ADC clock, so
//! their carrier phases keep constant offsets: the natural part for a three-antenna
//! interferometer (three channels for the antennas, the fourth free). Its ADCs output 2-bit
//! sign/magnitude samples per channel (see [`crate::signal::samples`], format
//! `MultiChannel2`).
//!
//! # Provenance of the register values (read this before flying it)
//! The NT1065 datasheet is not freely distributed and could not be consulted for this crate.
//! What is here comes from public code that configures the part in shipping hardware, and
//! every value is marked:
//!
//! * **(F)** from the public NT1065 configuration code of a commercial receiver's firmware
//!   (register addresses, the SPI frame, the chip-ID layout, the status bits, a complete
//!   working register set for GPS L1 on PLL A with a 10 MHz TCXO);
//! * **(I)** inferred by us from those values (field positions inside a register, e.g. that
//!   PLL A's `R` divider sits in bits 6–3 of register 43, which makes the published values
//!   give LOs of 1590 MHz and 1235 MHz, exactly the L1/G1 and L2/G2 plans they are used for);
//! * **(A)** assumed (the meaning of bit 0 of register 3 as "all channels on PLL A" when 0).
//!
//! Check them against the datasheet of your part revision before use; the driver reads back
//! the chip ID (1065) and checks PLL lock and the AOK flag, which catches gross errors.
//!
//! # SPI frame (F)
//! Two bytes, mode 0: `[address | R, data]`, `R = 0x80` for a read (the data byte then clocks
//! the register out), 0 for a write; addresses 0–127.

use crate::error::{Error, ErrorKind};
use core::fmt;
use embedded_hal::delay::DelayNs;
use embedded_hal::spi::SpiDevice;

/// Registers used by the driver (F unless marked).
pub mod reg {
    /// Chip ID bits 12–5 (F: `(r0 << 8 | r1) >> 3` = 1065).
    pub const ID_HIGH: u8 = 0;
    /// Chip ID bits 4–0 and release number in bits 2–0 (F).
    pub const ID_LOW_RELEASE: u8 = 1;
    /// IC mode, bits 1–0: 3 = active (F).
    pub const MODE: u8 = 2;
    /// TCXO frequency select and LO source (F; bit meanings I/A, see [`super::Nt1065Config`]).
    pub const TCXO_LO: u8 = 3;
    /// LPF auto-calibration: write 3 to run; bit 1 reads 1 when calibrated (F).
    pub const LPF_CALIBRATION: u8 = 4;
    /// AOK indicator mask (F: 0x1D ignores AGC errors).
    pub const AOK_MASK: u8 = 6;
    /// Status: bit 4 = AOK (F).
    pub const STATUS: u8 = 7;
    /// ADC / output clock divider, divides PLL A by `2 × value` (F).
    pub const CLOCK_DIVIDER: u8 = 11;
    /// Clock source and output signal type (F: 0x1C).
    pub const CLOCK_OUTPUT: u8 = 12;
    /// First register of channel 1; channel `k` (0–3) uses `13 + 7k … 19 + 7k` (F).
    pub const CHANNEL_BASE: u8 = 13;
    /// PLL A band and enable (F).
    pub const PLL_A_ENABLE: u8 = 41;
    /// PLL A `N[8:1]` (F).
    pub const PLL_A_N_HIGH: u8 = 42;
    /// PLL A `N[0]` (bit 7) and `R` (bits 6–3, I); bits 2–0 kept at 1 (F).
    pub const PLL_A_N_LOW_R: u8 = 43;
    /// PLL A status: bit 0 locked, bit 1 VCO above range, bit 2 VCO below range (F).
    pub const PLL_A_STATUS: u8 = 44;
    /// PLL B status, same bits (F).
    pub const PLL_B_STATUS: u8 = 48;
}

/// The chip ID the part reports.
pub const CHIP_ID: u16 = 1065;

/// SPI read flag in the address byte.
const READ: u8 = 0x80;

/// One RF channel's set-up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelSetup {
    /// Channel on (register `13 + 7k` bit 0, F).
    pub enabled: bool,
    /// Signal below the LO (lower sideband): register `13 + 7k` bit 1 (I: the published
    /// set-ups set it for GPS L1 under a 1590 MHz LO and clear it for GLONASS G1 above it).
    pub lower_sideband: bool,
    /// Low-pass filter code, register `14 + 7k` (F: 0x30 is used for GPS L1).
    pub lpf_code: u8,
    /// Registers `15 + 7k … 19 + 7k` as published for active channels (gain and ADC set-up,
    /// meaning not documented here; F: 0x0B, 0x34, 0xF1, 0xEA, 0x0B).
    pub tail: [u8; 5],
}

impl ChannelSetup {
    /// GPS L1 under a 1590 MHz LO (F).
    pub const GPS_L1: Self = Self {
        enabled: true,
        lower_sideband: true,
        lpf_code: 0x30,
        tail: [0x0B, 0x34, 0xF1, 0xEA, 0x0B],
    };

    /// A channel switched off.
    pub const OFF: Self = Self {
        enabled: false,
        lower_sideband: false,
        lpf_code: 0x30,
        tail: [0x0B, 0x34, 0xF1, 0xEA, 0x0B],
    };

    fn first_register(&self) -> u8 {
        u8::from(self.enabled) | (u8::from(self.lower_sideband) << 1)
    }
}

/// The whole configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Nt1065Config {
    /// TCXO frequency, Hz (10 MHz in the published set-up).
    pub tcxo_hz: u32,
    /// Register 3: bit 1 TCXO select, bit 0 LO source (A: 0 = all four channels on PLL A,
    /// 1 = channels 1–2 on A and 3–4 on B, which is what the published dual-band set-up
    /// writes).
    pub tcxo_lo_register: u8,
    /// PLL A feedback divider `N` (1–511): `LO = f_TCXO · N / R`.
    pub pll_a_n: u16,
    /// PLL A reference divider `R` (1–15).
    pub pll_a_r: u8,
    /// Register 11: the ADC clock is PLL A / (2 × value) (F: 0x0F → 53 MHz).
    pub clock_divider: u8,
    /// Register 12 (F: 0x1C).
    pub clock_output: u8,
    /// The four channels.
    pub channels: [ChannelSetup; 4],
}

impl Nt1065Config {
    /// Three antennas on GPS L1, all channels on PLL A: TCXO 10 MHz, `N = 159`, `R = 1`
    /// (LO 1590 MHz, IF = −14.58 MHz, i.e. L1 in the lower sideband), ADC clock 53 MHz,
    /// channels 1–3 on, channel 4 off.
    pub const fn three_antenna_l1() -> Self {
        Self {
            tcxo_hz: 10_000_000,
            tcxo_lo_register: 0x00,
            pll_a_n: 159,
            pll_a_r: 1,
            clock_divider: 0x0F,
            clock_output: 0x1C,
            channels: [
                ChannelSetup::GPS_L1,
                ChannelSetup::GPS_L1,
                ChannelSetup::GPS_L1,
                ChannelSetup::OFF,
            ],
        }
    }

    /// The LO of PLL A, Hz.
    pub fn lo_a_hz(&self) -> f64 {
        f64::from(self.tcxo_hz) * f64::from(self.pll_a_n) / f64::from(self.pll_a_r.max(1))
    }

    /// The ADC sample rate, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.lo_a_hz() / (2.0 * f64::from(self.clock_divider.max(1)))
    }

    /// The IF of GPS L1 (signal minus LO; negative in the lower sideband), Hz.
    pub fn l1_intermediate_frequency_hz(&self) -> f64 {
        crate::signal::GPS_L1_HZ - self.lo_a_hz()
    }

    /// The register writes of this configuration, in order: mode, TCXO/LO, AOK mask, clock,
    /// channels, PLL A, then the LPF calibration start.
    ///
    /// # Errors
    /// [`FrontEndError::InvalidConfig`] for `N` outside 1–511, `R` outside 1–15 or a zero
    /// clock divider.
    pub fn register_writes(&self) -> Result<[(u8, u8); 37], FrontEndError<()>> {
        if !(1..=511).contains(&self.pll_a_n)
            || !(1..=15).contains(&self.pll_a_r)
            || self.clock_divider == 0
        {
            return Err(FrontEndError::InvalidConfig);
        }
        let mut w = [(0u8, 0u8); 37];
        let mut k = 0;
        let mut push = |a: u8, v: u8| {
            if let Some(slot) = w.get_mut(k) {
                *slot = (a, v);
            }
            k += 1;
        };
        push(reg::MODE, 0x03);
        push(reg::TCXO_LO, self.tcxo_lo_register);
        push(reg::AOK_MASK, 0x1D);
        push(reg::CLOCK_DIVIDER, self.clock_divider);
        push(reg::CLOCK_OUTPUT, self.clock_output);
        for (c, ch) in self.channels.iter().enumerate() {
            let base = reg::CHANNEL_BASE + 7 * c as u8;
            push(base, ch.first_register());
            push(base + 1, ch.lpf_code);
            for (j, v) in ch.tail.iter().enumerate() {
                push(base + 2 + j as u8, *v);
            }
        }
        push(reg::PLL_A_ENABLE, 0x03);
        push(reg::PLL_A_N_HIGH, (self.pll_a_n >> 1) as u8);
        push(
            reg::PLL_A_N_LOW_R,
            (((self.pll_a_n & 1) as u8) << 7) | ((self.pll_a_r & 0x0F) << 3) | 0x01,
        );
        push(reg::LPF_CALIBRATION, 0x03);
        Ok(w)
    }
}

/// Status of one synthesizer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PllStatus {
    /// Locked.
    pub locked: bool,
    /// VCO control voltage above its range.
    pub vco_high: bool,
    /// VCO control voltage below its range.
    pub vco_low: bool,
}

/// The driver, over any embedded-hal 1.0 [`SpiDevice`] (chip select handled by the device).
#[derive(Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Nt1065<SPI> {
    spi: SPI,
}

impl<SPI: SpiDevice> Nt1065<SPI> {
    /// Wraps the SPI device (no bus traffic).
    pub fn new(spi: SPI) -> Self {
        Self { spi }
    }

    /// Releases the SPI device.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// Reads register `address` (0–127).
    ///
    /// # Errors
    /// [`FrontEndError::InvalidConfig`] for an address above 127, [`FrontEndError::Spi`].
    pub fn read_register(&mut self, address: u8) -> Result<u8, FrontEndError<SPI::Error>> {
        if address > 0x7F {
            return Err(FrontEndError::InvalidConfig);
        }
        let mut frame = [address | READ, 0];
        self.spi
            .transfer_in_place(&mut frame)
            .map_err(FrontEndError::Spi)?;
        Ok(frame[1])
    }

    /// Writes register `address` (0–127).
    ///
    /// # Errors
    /// [`FrontEndError::InvalidConfig`] for an address above 127, [`FrontEndError::Spi`].
    pub fn write_register(
        &mut self,
        address: u8,
        value: u8,
    ) -> Result<(), FrontEndError<SPI::Error>> {
        if address > 0x7F {
            return Err(FrontEndError::InvalidConfig);
        }
        self.spi
            .write(&[address, value])
            .map_err(FrontEndError::Spi)
    }

    /// Chip ID and release number (registers 0–1).
    ///
    /// # Errors
    /// [`FrontEndError::Spi`].
    pub fn chip_id(&mut self) -> Result<(u16, u8), FrontEndError<SPI::Error>> {
        let word = (u16::from(self.read_register(reg::ID_HIGH)?) << 8)
            | u16::from(self.read_register(reg::ID_LOW_RELEASE)?);
        Ok((word >> 3, (word & 7) as u8))
    }

    /// Checks the chip ID, then writes the configuration.
    ///
    /// # Errors
    /// [`FrontEndError::WrongChip`] (nothing is written), [`FrontEndError::InvalidConfig`],
    /// [`FrontEndError::Spi`].
    pub fn configure(&mut self, config: &Nt1065Config) -> Result<(), FrontEndError<SPI::Error>> {
        // (`register_writes` refuses only with `InvalidConfig`, re-typed for this bus)
        let writes = config
            .register_writes()
            .map_err(|_| FrontEndError::InvalidConfig)?;
        let (id, _) = self.chip_id()?;
        if id != CHIP_ID {
            return Err(FrontEndError::WrongChip);
        }
        for (a, v) in writes {
            self.write_register(a, v)?;
        }
        Ok(())
    }

    /// PLL A's status (register 44).
    ///
    /// # Errors
    /// [`FrontEndError::Spi`].
    pub fn pll_a_status(&mut self) -> Result<PllStatus, FrontEndError<SPI::Error>> {
        let s = self.read_register(reg::PLL_A_STATUS)?;
        Ok(PllStatus {
            locked: s & 1 != 0,
            vco_high: s & 2 != 0,
            vco_low: s & 4 != 0,
        })
    }

    /// The AOK flag (register 7 bit 4): PLLs locked, LPF calibrated, chip active.
    ///
    /// # Errors
    /// [`FrontEndError::Spi`].
    pub fn is_ok(&mut self) -> Result<bool, FrontEndError<SPI::Error>> {
        Ok(self.read_register(reg::STATUS)? & 0x10 != 0)
    }

    /// Polls AOK and PLL A lock every millisecond, at most `max_ms` times.
    ///
    /// # Errors
    /// [`FrontEndError::NotReady`] when the bound is reached, [`FrontEndError::Spi`].
    pub fn wait_ready<D: DelayNs>(
        &mut self,
        delay: &mut D,
        max_ms: u16,
    ) -> Result<(), FrontEndError<SPI::Error>> {
        for _ in 0..max_ms {
            if self.is_ok()? && self.pll_a_status()?.locked {
                return Ok(());
            }
            delay.delay_ms(1);
        }
        Err(FrontEndError::NotReady)
    }
}

/// Errors of the front-end drivers ([`crate::frontend`]); `E` is the SPI bus error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrontEndError<E> {
    /// The SPI transfer failed.
    #[error("SPI error: {0:?}")]
    Spi(E),
    /// A configuration value is out of range (PLL dividers, clock divider, register address).
    #[error("front-end configuration out of range")]
    InvalidConfig,
    /// The chip ID read back is not the expected part's; nothing was written.
    #[error("unexpected chip ID")]
    WrongChip,
    /// The part did not report ready (PLL lock, AOK) within the polling bound.
    #[error("front end not ready within the polling bound")]
    NotReady,
}

impl<E: fmt::Debug> Error for FrontEndError<E> {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::InvalidConfig | Self::WrongChip => ErrorKind::InvalidInput,
            Self::Spi(_) | Self::NotReady => ErrorKind::NotConverged,
        }
    }
}
