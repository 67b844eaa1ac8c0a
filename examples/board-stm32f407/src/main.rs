//! gnss-attitude on an STM32F407 Discovery-class board (168 MHz Cortex-M4F).
//!
//! ```text
//!  NT1065 ──SPI2 (PB13 SCK, PB14 MISO, PB15 MOSI, PB12 CS)── registers (core driver)
//!     │ CLK ─────────────────────────── DCMI_PIXCLK (PA6)
//!     │ ch1..ch4 SIGN/MAG (8 lines) ──── DCMI_D0..D7 (PC6 PC7 PE0 PE1 PE4 PB6 PE5 PE6)
//!     │                                  DCMI_HSYNC (PA4) ← PD0, DCMI_VSYNC (PB7) ← PD1
//!     ▼                                  (GPIO-driven: one endless "frame")
//!  DCMI ──DMA2 stream 1 ch 1, double buffer──► 3 × 1 ms of bytes ─► decode (MultiChannel2)
//!       ──► SampleReceiver (acquisition, 2 channels, adapter) ──► AttitudeReceiver
//!  L3GD20-class gyro ──SPI3 (PC10 SCK, PC11 MISO, PC12 MOSI, PA15 CS)── every 10 ms
//!  attitude, events, overruns ──defmt over RTT──► probe-rs
//! ```
//!
//! **Why DCMI.** The NT1065 puts its 2-bit ADC outputs (SIGN and MAG of each of its four
//! channels) and the ADC clock on parallel CMOS pins; its SPI port is for the registers only.
//! The evaluation board captures that parallel byte per clock (with a USB 3 controller's
//! parallel port); on the STM32F407 the peripheral that latches 8 parallel bits on an
//! external clock and hands them to DMA is the camera interface, DCMI. One byte per sample
//! instant is the core's `SampleFormat::MultiChannel2` layout (channel `c` in bits `2c+1`,
//! `2c`). HSYNC and VSYNC are driven from GPIOs: VSYNC goes active once after capture is
//! enabled, and the capture then runs as one endless frame.
//!
//! **Real time.** The software correlators of the core keep up with about one channel at
//! 2.6 Msps on this CPU (README budgets); at the 5 Msps set here the firmware cannot process
//! every millisecond: it processes the newest buffer, counts the ones the DMA overwrote
//! before they were processed (`overruns`) and keeps the stream continuous for the channels
//! by releasing and re-acquiring after a gap. A flight receiver puts a hardware correlator in
//! front of `AttitudeReceiver::push_observation` instead (see the C ABI and the README).
//!
//! **Sample rate (assumed).** The published NT1065 register set clocks the ADC at 53 MHz
//! (register 11 = 15). This firmware writes 159 (PLL A 1590 MHz / 318 = 5 MHz, 5000 samples
//! per 1 ms epoch) on the assumption that register 11 takes that value; check it against the
//! datasheet of your part.
#![no_std]
#![no_main]

mod gyro;

use cortex_m_rt::entry;
use embedded_hal_bus::spi::ExclusiveDevice;
use defmt_rtt as _;
use panic_probe as _;

use embedded_hal::spi::{Mode, Phase, Polarity};
use stm32f4xx_hal::dma::{config::DmaConfig, PeripheralToMemory, Stream1, StreamsTuple, Transfer};
use stm32f4xx_hal::pac::{self, DCMI, DMA2};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config;
use stm32f4xx_hal::spi::Spi;

use gnss_attitude::frontend::nt1065::{Nt1065, Nt1065Config};
use gnss_attitude::receiver::example::antennas;
use gnss_attitude::receiver::{
    GyroConfig, ReceiverConfig, SampleFrontConfig, SampleReceiver,
};
use gnss_attitude::signal::{Prn, SampleBlock, SampleFormat};

use gyro::{L3gd20, RateGyro};

/// Sample rate set in the NT1065 (register 11 = 159, see the crate docs), Hz.
const SAMPLE_RATE_HZ: f64 = 5.0e6;
/// NT1065 register 11: PLL A / (2 × 159) = 5 MHz.
const CLOCK_DIVIDER: u8 = 159;
/// Samples (bytes) per 1 ms epoch.
const EPOCH_SAMPLES: usize = 5000;
/// 32-bit DMA words per buffer (DCMI packs four bytes per word).
const WORDS: usize = EPOCH_SAMPLES / 4;
/// Gyro sample interval, s (every ten epochs).
const GYRO_H: f32 = 0.01;
/// Longest wait for the NT1065's PLL and AOK, ms.
const FRONT_END_READY_MS: u16 = 200;
/// Tracking channels and acquisition FFT size that fit the 128 KiB of DMA-reachable RAM.
type Front = SampleReceiver<2, 1024>;

type Buffer = &'static mut [u32; WORDS];
type Capture = Transfer<Stream1<DMA2>, 1, DCMI, PeripheralToMemory, Buffer>;

#[entry]
fn main() -> ! {
    let Some(dp) = pac::Peripherals::take() else {
        panic!("peripherals taken twice");
    };
    let mut rcc = dp.RCC.freeze(Config::hse(8.MHz()).sysclk(168.MHz()));
    let mut delay = dp.TIM5.delay_us(&mut rcc);
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    let gpioc = dp.GPIOC.split(&mut rcc);
    let gpiod = dp.GPIOD.split(&mut rcc);
    let gpioe = dp.GPIOE.split(&mut rcc);

    // NT1065 over SPI2, mode 0, the core's driver
    let mode0 = Mode { polarity: Polarity::IdleLow, phase: Phase::CaptureOnFirstTransition };
    let spi2 = Spi::new(
        dp.SPI2,
        (Some(gpiob.pb13), Some(gpiob.pb14), Some(gpiob.pb15)),
        mode0,
        1.MHz(),
        &mut rcc,
    );
    let nt_cs = gpiob.pb12.into_push_pull_output();
    let Ok(nt_spi) = ExclusiveDevice::new_no_delay(spi2, nt_cs);
    let mut front_end = Nt1065::new(nt_spi);
    let mut nt = Nt1065Config::three_antenna_l1();
    nt.clock_divider = CLOCK_DIVIDER;
    match front_end
        .chip_id()
        .and_then(|id| front_end.configure(&nt).map(|()| id))
        .and_then(|id| front_end.wait_ready(&mut delay, FRONT_END_READY_MS).map(|()| id))
    {
        Ok((id, release)) => defmt::info!("NT1065 id {} release {}, PLL A locked", id, release),
        Err(e) => defmt::error!("NT1065 set-up failed: {}", defmt::Debug2Format(&e)),
    }

    // gyro over SPI3, mode 3
    let mode3 = Mode { polarity: Polarity::IdleHigh, phase: Phase::CaptureOnSecondTransition };
    let spi3 = Spi::new(
        dp.SPI3,
        (Some(gpioc.pc10), Some(gpioc.pc11), Some(gpioc.pc12)),
        mode3,
        2.MHz(),
        &mut rcc,
    );
    let gyro_cs = gpioa.pa15.into_push_pull_output();
    let mut gyro = ExclusiveDevice::new_no_delay(spi3, gyro_cs)
        .ok()
        .and_then(|spi| L3gd20::new(spi).map_err(|e| defmt::error!("gyro: {}", defmt::Debug2Format(&e))).ok());

    // DCMI pins, sync lines from GPIO (inactive until the capture is armed)
    let _data = (
        gpioc.pc6.into_alternate::<13>(),
        gpioc.pc7.into_alternate::<13>(),
        gpioe.pe0.into_alternate::<13>(),
        gpioe.pe1.into_alternate::<13>(),
        gpioe.pe4.into_alternate::<13>(),
        gpiob.pb6.into_alternate::<13>(),
        gpioe.pe5.into_alternate::<13>(),
        gpioe.pe6.into_alternate::<13>(),
        gpioa.pa6.into_alternate::<13>(),
        gpioa.pa4.into_alternate::<13>(),
        gpiob.pb7.into_alternate::<13>(),
    );
    let mut hsync = gpiod.pd0.into_push_pull_output();
    let mut vsync = gpiod.pd1.into_push_pull_output();
    hsync.set_high(); // HSPOL = 0: high is "line active"
    vsync.set_low(); // VSPOL = 0: low is blanking until the capture is armed

    let streams = StreamsTuple::new(dp.DMA2, &mut rcc);
    let (Some(a), Some(b), Some(spare)) = (
        cortex_m::singleton!(: [u32; WORDS] = [0; WORDS]),
        cortex_m::singleton!(: [u32; WORDS] = [0; WORDS]),
        cortex_m::singleton!(: [u32; WORDS] = [0; WORDS]),
    ) else {
        panic!("buffers taken twice");
    };
    enable_dcmi_clock();
    configure_dcmi(&dp.DCMI);
    let config = DmaConfig::default()
        .memory_increment(true)
        .double_buffer(true)
        .transfer_complete_interrupt(false);
    let mut capture: Capture = Transfer::init_peripheral_to_memory(streams.1, dp.DCMI, a, Some(b), config);
    capture.start(|dcmi| {
        dcmi.cr().modify(|_, w| w.capture().set_bit());
    });
    vsync.set_high(); // frame start: the capture runs from here on

    let receiver = ReceiverConfig::gps_l1(antennas(), Some(GyroConfig::mems(GYRO_H, None)));
    let mut front = SampleFrontConfig::leo_complex(SAMPLE_RATE_HZ);
    let if_hz = alias(nt.l1_intermediate_frequency_hz(), SAMPLE_RATE_HZ);
    front.acquisition.intermediate_frequency_hz = if_hz;
    front.channel = gnss_attitude::tracking::ChannelConfig::leo(SAMPLE_RATE_HZ, if_hz);
    let Ok(mut rx) = Front::new(receiver, front) else {
        panic!("receiver configuration");
    };
    defmt::info!("receiver: {} B, IF {} Hz", core::mem::size_of::<Front>(), if_hz as f32);

    run(&mut capture, Some(spare), &mut rx, gyro.as_mut())
}

/// The loop: each filled buffer is swapped for the spare, decoded and pushed; the gyro every
/// ten epochs; the attitude and events once a second.
fn run(
    capture: &mut Capture,
    mut spare: Option<Buffer>,
    rx: &mut Front,
    mut gyro: Option<&mut impl RateGyro>,
) -> ! {
    let format = SampleFormat::MultiChannel2 { channels: 3 };
    let mut planes = [[0i8; EPOCH_SAMPLES]; 3];
    let mut epoch: u64 = 0;
    let mut overruns: u32 = 0;
    let mut prn_cursor: u8 = 0;
    loop {
        if !capture.is_transfer_complete() {
            continue;
        }
        let Some(empty) = spare.take() else {
            continue;
        };
        let filled = match capture.next_transfer(empty) {
            Ok((filled, _)) => filled,
            Err(e) => {
                // the DMA wrapped before this buffer was handed back: samples were lost
                overruns = overruns.saturating_add(1);
                spare = Some(dma_error_buffer(e));
                continue;
            }
        };
        let bytes: &[u8] = bytemuck::cast_slice(&filled[..]);
        for (channel, plane) in planes.iter_mut().enumerate() {
            if format.decode(bytes, channel, plane, &mut []).is_err() {
                defmt::warn!("decode failed");
            }
        }
        spare = Some(filled);
        let first = epoch.saturating_mul(EPOCH_SAMPLES as u64);
        let [pa, pb, pc] = &planes;
        if let Ok(block) = SampleBlock::real(first, [&pa[..], &pb[..], &pc[..]]) {
            match rx.push_samples(&block) {
                Ok(report) if report.released > 0 => defmt::info!("{}", report),
                Ok(_) => {}
                Err(e) => defmt::warn!("samples: {}", e),
            }
        }
        // one PRN searched per second while a channel is free
        if epoch % 1000 == 0 {
            prn_cursor = prn_cursor % 32 + 1;
            if let Some(prn) = Prn::new(prn_cursor) {
                if let Err(e) = rx.search(prn, pa, None, first) {
                    defmt::debug!("search {}: {}", prn_cursor, e);
                }
            }
        }
        if epoch % 10 == 9 {
            if let Some(g) = gyro.as_deref_mut() {
                if let Ok(rate) = g.rate() {
                    let theta = rate.map(|w| w * GYRO_H);
                    if let Err(e) = rx.receiver_mut().push_gyro_increment(&theta) {
                        defmt::warn!("gyro: {}", e);
                    }
                }
            }
        }
        if epoch % 1000 == 999 {
            let att = rx.attitude();
            defmt::info!(
                "epoch {} source {} q [{}, {}, {}, {}] health {} overruns {}",
                att.epoch, att.source, att.q_rb.w, att.q_rb.x, att.q_rb.y, att.q_rb.z,
                att.health, overruns
            );
            while let Some(event) = rx.receiver_mut().pop_event() {
                defmt::info!("event {}", event);
            }
        }
        epoch += 1;
    }
}

/// `f` folded into `(−fs/2, fs/2]`: the IF seen after real sampling at `fs`.
fn alias(f: f64, fs: f64) -> f64 {
    let r = f - fs * libm_round(f / fs);
    if r <= -fs / 2.0 { r + fs } else { r }
}

fn libm_round(x: f64) -> f64 {
    // f64 rounding without std: the values here are small (|x| < 1e4)
    let t = x as i64 as f64;
    if x - t >= 0.5 { t + 1.0 } else if t - x > 0.5 { t - 1.0 } else { t }
}

/// Clocks the DCMI (RCC AHB2ENR.DCMIEN; the HAL has no enable for it).
fn enable_dcmi_clock() {
    // SAFETY: a single read-modify-write of RCC_AHB2ENR before any interrupt is enabled
    // (nothing else touches the register concurrently); setting DCMIEN only clocks the DCMI.
    let rcc = unsafe { &*pac::RCC::ptr() };
    rcc.ahb2enr().modify(|_, w| w.dcmien().set_bit());
}

/// DCMI: 8-bit data latched on the rising PIXCLK edge, hardware sync with both sync lines
/// "active" when high (HSPOL = VSPOL = 0 marks low as blanking), every frame, continuous
/// mode; enabled (the capture bit is set once the DMA runs).
fn configure_dcmi(dcmi: &DCMI) {
    dcmi.cr().write(|w| {
        w.pckpol().set_bit();
        w.hspol().clear_bit();
        w.vspol().clear_bit();
        w.ess().clear_bit();
        w.cm().clear_bit();
        w.jpeg().clear_bit();
        w.enable().set_bit()
    });
}

/// The buffer a failed `next_transfer` hands back.
fn dma_error_buffer(e: stm32f4xx_hal::dma::DMAError<Buffer>) -> Buffer {
    match e {
        stm32f4xx_hal::dma::DMAError::NotReady(b)
        | stm32f4xx_hal::dma::DMAError::SmallBuffer(b)
        | stm32f4xx_hal::dma::DMAError::Overrun(b) => b,
    }
}
