//! The gyro behind an `embedded-hal` 1.0 trait: [`RateGyro`] is what the firmware needs,
//! [`L3gd20`] one implementation over [`SpiDevice`] (ST L3GD20 / I3G4250D register map).

use embedded_hal::spi::{Operation, SpiDevice};

/// A three-axis rate gyro sampled by the firmware.
pub trait RateGyro {
    /// The bus error.
    type Error;
    /// One rate sample, body axes, rad/s.
    fn rate(&mut self) -> Result<[f32; 3], Self::Error>;
}

/// WHO_AM_I register and the answers of the parts this driver knows.
const WHO_AM_I: u8 = 0x0F;
const IDS: [u8; 3] = [0xD4, 0xD3, 0xD7];
/// CTRL_REG1: output data rate 95 Hz, all axes on, normal mode.
const CTRL_REG1: u8 = 0x20;
const CTRL_REG1_95HZ_ON: u8 = 0x0F;
/// OUT_X_L, first of the six output registers.
const OUT_X_L: u8 = 0x28;
/// Read bit and address auto-increment bit of the SPI frame.
const READ: u8 = 0x80;
const AUTO_INCREMENT: u8 = 0x40;
/// Sensitivity at ±250 °/s full scale: 8.75 m°/s per digit, in rad/s.
const RAD_S_PER_DIGIT: f32 = 8.75e-3 * core::f32::consts::PI / 180.0;

/// Error of [`L3gd20`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum GyroError<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// WHO_AM_I answered an unknown identity.
    UnknownDevice(u8),
}

/// An L3GD20-class gyro on SPI (mode 3).
pub struct L3gd20<SPI> {
    spi: SPI,
}

impl<SPI: SpiDevice> L3gd20<SPI> {
    /// Checks the identity and starts the gyro at 95 Hz.
    ///
    /// # Errors
    /// [`GyroError::UnknownDevice`], [`GyroError::Spi`].
    pub fn new(mut spi: SPI) -> Result<Self, GyroError<SPI::Error>> {
        let mut id = [0u8];
        spi.transaction(&mut [Operation::Write(&[WHO_AM_I | READ]), Operation::Read(&mut id)])
            .map_err(GyroError::Spi)?;
        if !IDS.contains(&id[0]) {
            return Err(GyroError::UnknownDevice(id[0]));
        }
        spi.write(&[CTRL_REG1, CTRL_REG1_95HZ_ON])
            .map_err(GyroError::Spi)?;
        Ok(Self { spi })
    }
}

impl<SPI: SpiDevice> RateGyro for L3gd20<SPI> {
    type Error = GyroError<SPI::Error>;

    fn rate(&mut self) -> Result<[f32; 3], Self::Error> {
        let mut raw = [0u8; 6];
        self.spi
            .transaction(&mut [
                Operation::Write(&[OUT_X_L | READ | AUTO_INCREMENT]),
                Operation::Read(&mut raw),
            ])
            .map_err(GyroError::Spi)?;
        let [xl, xh, yl, yh, zl, zh] = raw;
        Ok([[xl, xh], [yl, yh], [zl, zh]].map(|b| f32::from(i16::from_le_bytes(b)) * RAD_S_PER_DIGIT))
    }
}
