//! The NT1065 driver against a mocked SPI bus (embedded-hal-mock): the exact frames of the
//! chip-ID check, the configuration and the status polling, and its refusals.

use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as T};
use gnss_attitude::frontend::nt1065::{reg, ChannelSetup, Nt1065, Nt1065Config};
use gnss_attitude::frontend::FrontEndError;

/// A register read: `[addr | 0x80, 0]` out, `[_, value]` back.
fn read(addr: u8, value: u8) -> Vec<T<u8>> {
    vec![
        T::transaction_start(),
        T::transfer_in_place(vec![addr | 0x80, 0], vec![0, value]),
        T::transaction_end(),
    ]
}

fn write(addr: u8, value: u8) -> Vec<T<u8>> {
    vec![
        T::transaction_start(),
        T::write_vec(vec![addr, value]),
        T::transaction_end(),
    ]
}

/// 1065 << 3 | release 2 = 0x214A: registers 0 and 1 read 0x21, 0x4A.
fn id_reads() -> Vec<T<u8>> {
    [read(0, 0x21), read(1, 0x4A)].concat()
}

#[test]
fn three_antenna_l1_plan_is_consistent() {
    let c = Nt1065Config::three_antenna_l1();
    assert_eq!(c.lo_a_hz(), 1.59e9);
    assert_eq!(c.sample_rate_hz(), 53e6);
    assert!((c.l1_intermediate_frequency_hz() + 14.58e6).abs() < 1.0);
    // All three antenna channels identical (phase-coherent), the fourth off.
    assert_eq!(c.channels[0], c.channels[1]);
    assert_eq!(c.channels[1], c.channels[2]);
    assert!(!c.channels[3].enabled);
}

#[test]
fn configure_checks_the_id_then_writes_the_documented_registers() {
    let config = Nt1065Config::three_antenna_l1();
    let writes = config.register_writes().unwrap();
    // Spot checks of the documented values.
    assert!(writes.contains(&(reg::MODE, 0x03)));
    assert!(writes.contains(&(reg::TCXO_LO, 0x00)));
    assert!(writes.contains(&(reg::CLOCK_DIVIDER, 0x0F)));
    assert!(
        writes.contains(&(13, 0x03))
            && writes.contains(&(20, 0x03))
            && writes.contains(&(27, 0x03))
    );
    assert!(writes.contains(&(34, 0x00)));
    // N = 159 = 0b1001_1111: N[8:1] = 0x4F, N[0] = 1 → bit 7; R = 1 → bits 6–3.
    assert!(writes.contains(&(reg::PLL_A_N_HIGH, 0x4F)));
    assert!(writes.contains(&(reg::PLL_A_N_LOW_R, 0x89)));
    assert_eq!(writes.last(), Some(&(reg::LPF_CALIBRATION, 0x03)));

    let mut expected = id_reads();
    for (a, v) in writes {
        expected.extend(write(a, v));
    }
    let spi = SpiMock::new(&expected);
    let mut fe = Nt1065::new(spi);
    fe.configure(&config).unwrap();
    fe.release().done();
}

#[test]
fn wrong_chip_is_refused_before_any_write() {
    let spi = SpiMock::new(&[read(0, 0x12), read(1, 0x34)].concat());
    let mut fe = Nt1065::new(spi);
    assert_eq!(
        fe.configure(&Nt1065Config::three_antenna_l1()),
        Err(FrontEndError::WrongChip)
    );
    fe.release().done();
}

#[test]
fn invalid_dividers_are_refused_without_bus_traffic() {
    let mut c = Nt1065Config::three_antenna_l1();
    c.pll_a_r = 0;
    let spi = SpiMock::new(&[]);
    let mut fe = Nt1065::new(spi);
    assert_eq!(fe.configure(&c), Err(FrontEndError::InvalidConfig));
    assert_eq!(
        fe.write_register(0x80, 1),
        Err(FrontEndError::InvalidConfig)
    );
    fe.release().done();
    let mut c = Nt1065Config::three_antenna_l1();
    c.channels[0] = ChannelSetup::OFF;
    c.pll_a_n = 600;
    assert!(c.register_writes().is_err());
}

#[test]
fn wait_ready_polls_aok_and_pll_lock_with_a_bound() {
    // Not ready, then ready: AOK set and PLL A locked.
    let expected = [read(7, 0x00), read(7, 0x10), read(44, 0x01)].concat();
    let spi = SpiMock::new(&expected);
    let mut fe = Nt1065::new(spi);
    fe.wait_ready(&mut NoopDelay::new(), 10).unwrap();
    fe.release().done();
    // Never ready: the bound ends it.
    let expected = [read(7, 0x10), read(44, 0x04), read(7, 0x10), read(44, 0x04)].concat();
    let spi = SpiMock::new(&expected);
    let mut fe = Nt1065::new(spi);
    assert_eq!(
        fe.wait_ready(&mut NoopDelay::new(), 2),
        Err(FrontEndError::NotReady)
    );
    fe.release().done();
}
