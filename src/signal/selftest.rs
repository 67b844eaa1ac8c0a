//! A deterministic correlator computation that the firmware runs on the target and compares
//! bit for bit with the host (the correlator is integer-only, so the outputs must be equal).

use super::correlator::{Correlator, CorrelatorConfig, EpochCorrelations};
use super::{Prn, SampleBlock};
use crate::signal::SignalError;

/// Samples per antenna and component of the self-test (one 1 ms code period at 2.6 Msps plus
/// margin).
pub const SIGNAL_SELF_TEST_LEN: usize = 2608;

/// Sample rate of the self-test, Hz.
pub const SIGNAL_SELF_TEST_RATE_HZ: f64 = 2.6e6;

/// Deterministic pseudo-random samples in `−32..=31` (xorshift32 from `seed`), usable in
/// `const` context (the firmware builds its inputs with it into flash).
pub const fn signal_self_test_samples(seed: u32) -> [i8; SIGNAL_SELF_TEST_LEN] {
    let mut out = [0i8; SIGNAL_SELF_TEST_LEN];
    let mut x = seed | 1;
    let mut k = 0;
    while k < SIGNAL_SELF_TEST_LEN {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        out[k] = ((x >> 24) as i8) >> 2;
        k += 1;
    }
    out
}

/// One code period of the three-antenna correlator (PRN 5, 2.6 Msps complex, Doppler
/// 2345 Hz, E/P/L offset 0.5 chip) over the given samples.
///
/// # Errors
/// [`SignalError`] from the block or the correlator (not for the self-test's own inputs).
pub fn run_correlator_self_test(
    i: [&[i8]; 3],
    q: [&[i8]; 3],
) -> Result<Option<EpochCorrelations<3>>, SignalError> {
    let config = CorrelatorConfig {
        sample_rate_hz: SIGNAL_SELF_TEST_RATE_HZ,
        intermediate_frequency_hz: 0.0,
        early_late_offset_chips: 0.5,
        slave_taps: crate::signal::SlaveTaps::All,
    };
    let prn = Prn::new(5).ok_or(SignalError::InvalidConfig)?;
    let mut correlator = Correlator::<3>::new(prn, &config)?;
    correlator.set_carrier_frequency(2345.0)?;
    correlator.set_code_phase(0.0)?;
    let block = SampleBlock::complex(0, i, q)?;
    let mut cursor = 0;
    correlator.run(&block, &mut cursor)
}
