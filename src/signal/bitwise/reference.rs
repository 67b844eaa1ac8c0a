//! The scalar reference of the bit-parallel correlator: the same replica and the same sums,
//! one sample at a time, with `i64` accumulators and the per-sample definitions of
//! [`carrier`](super::carrier) and [`code`](super::code). Slow and obviously correct; the
//! property tests compare [`BitCorrelator`](super::BitCorrelator) with it bit for bit.

use super::block::BitBlock;
use super::carrier::{three_level_replica, two_level_replica, CarrierLevels};
use super::code::replica_chip;
use super::correlator::{BitCorrelatorConfig, BitCorrelatorError};
use super::planes::{PlaneFormat, WORD_SAMPLES};
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ};
use crate::signal::correlator::{EpochCorrelations, Iq, SlaveTaps, Taps};
use crate::signal::nco::{CarrierNco, CodeNco, CODE_WRAP};

/// The scalar reference correlator (same NCO interface as
/// [`BitCorrelator`](super::BitCorrelator), public NCO state for tests).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScalarReference<const A: usize> {
    prn: Prn,
    format: PlaneFormat,
    levels: CarrierLevels,
    slave_taps: SlaveTaps,
    /// Carrier NCO (phase and step, 2⁻³² cycle).
    pub carrier: CarrierNco,
    /// Code NCO (phase and step, 2⁻³² chip).
    pub code: CodeNco,
    /// Total carrier phase, 2⁻³² cycle (as [`BitCorrelator::carrier_phase_total`]).
    ///
    /// [`BitCorrelator::carrier_phase_total`]: super::BitCorrelator::carrier_phase_total
    pub carrier_total: i64,
    table_step: u64,
    /// Tap offsets in samples: early `+d`, prompt 0, late `−d`, noise `−D_n`.
    offsets: [i64; 4],
    sums: [[(i64, i64); 4]; A],
    samples: u32,
    first: Option<(u64, u64, i64)>,
    partial: bool,
}

impl<const A: usize> ScalarReference<A> {
    /// The reference for `prn` and `config` (NCOs as [`BitCorrelator::new`] sets them).
    ///
    /// [`BitCorrelator::new`]: super::BitCorrelator::new
    ///
    /// # Errors
    /// As [`BitCorrelatorConfig::validate`].
    pub fn new(prn: Prn, config: &BitCorrelatorConfig) -> Result<Self, BitCorrelatorError> {
        config.validate(prn)?;
        let c = &config.correlator;
        let step = CodeNco::step_for(CA_CHIP_RATE_HZ, c.sample_rate_hz);
        let d = c.early_late_offset_samples() as i64;
        Ok(Self {
            prn,
            format: config.format,
            levels: config.carrier,
            slave_taps: c.slave_taps,
            carrier: CarrierNco {
                phase: 0,
                step: CarrierNco::step_for(c.intermediate_frequency_hz, c.sample_rate_hz),
            },
            code: CodeNco { phase: 0, step },
            carrier_total: 0,
            table_step: step,
            offsets: [d, 0, -d, -(config.noise_delay_samples(prn) as i64)],
            sums: [[(0, 0); 4]; A],
            samples: 0,
            first: None,
            partial: true,
        })
    }

    /// Discards the integration in progress (the next output is partial).
    pub fn reset_integration(&mut self) {
        self.sums = [[(0, 0); 4]; A];
        self.samples = 0;
        self.first = None;
        self.partial = true;
    }

    /// As [`BitCorrelator::run`](super::BitCorrelator::run), one sample at a time.
    ///
    /// # Errors
    /// [`BitCorrelatorError::CursorOutOfRange`], [`BitCorrelatorError::FormatMismatch`].
    pub fn run(
        &mut self,
        block: &BitBlock<'_, A>,
        cursor: &mut usize,
    ) -> Result<Option<EpochCorrelations<A>>, BitCorrelatorError> {
        let start = *cursor;
        if start > block.len() {
            return Err(BitCorrelatorError::CursorOutOfRange);
        }
        if block.format() != self.format {
            return Err(BitCorrelatorError::FormatMismatch);
        }
        let to_wrap = self.code.samples_to_wrap();
        let n = ((block.len() - start) as u64).min(to_wrap) as usize;
        if n == 0 {
            return Ok(None);
        }
        if self.first.is_none() {
            let at = block.first_sample().wrapping_add(start as u64);
            self.first = Some((at, self.code.phase, self.carrier_total));
        }
        for p in start..start + n {
            self.sample(block, start, p);
        }
        let advance = (n as u64).wrapping_mul(self.code.step);
        self.code.phase = self.code.phase.wrapping_add(advance);
        let adv = self.carrier.step.wrapping_mul(n as u32);
        self.carrier.phase = self.carrier.phase.wrapping_add(adv);
        self.carrier_total = self
            .carrier_total
            .wrapping_add(i64::from(self.carrier.step as i32) * n as i64);
        self.samples = self.samples.saturating_add(n as u32);
        *cursor = start + n;
        if (n as u64) < to_wrap {
            return Ok(None);
        }
        self.code.phase = self.code.phase.wrapping_sub(CODE_WRAP);
        let (first_sample, code_phase_at_first, carrier_phase_at_first) =
            self.first.unwrap_or_default();
        let mut taps = [Taps::default(); A];
        for (a, (t, s)) in taps.iter_mut().zip(self.sums.iter()).enumerate() {
            let iq = |k: usize| {
                let (i, q) = s.get(k).copied().unwrap_or_default();
                Iq {
                    i: i as i32,
                    q: q as i32,
                }
            };
            t.prompt = iq(1);
            if a == 0 || self.slave_taps == SlaveTaps::All {
                t.early = iq(0);
                t.late = iq(2);
                t.noise = iq(3);
            }
        }
        let out = EpochCorrelations {
            taps,
            samples: self.samples,
            first_sample,
            code_phase_at_first,
            carrier_phase_at_first,
            complete: !self.partial,
        };
        self.sums = [[(0, 0); 4]; A];
        self.samples = 0;
        self.first = None;
        self.partial = false;
        Ok(Some(out))
    }

    /// Adds block sample `p` (the span starts at `start` with the NCOs as they are).
    fn sample(&mut self, block: &BitBlock<'_, A>, start: usize, p: usize) {
        let k = (p - start) as u32;
        let phase = self
            .carrier
            .phase
            .wrapping_add(self.carrier.step.wrapping_mul(k));
        let (c, s) = match self.levels {
            CarrierLevels::Two => two_level_replica(phase),
            CarrierLevels::Three => three_level_replica(phase),
        };
        let (c, s) = (i64::from(c), i64::from(s));
        let mut code = [0i64; 4];
        for (t, o) in code.iter_mut().zip(self.offsets) {
            *t = 1 - 2 * i64::from(self.code_bit(start, p as i64 + o));
        }
        for (a, sums) in self.sums.iter_mut().enumerate() {
            let Some(planes) = block.planes(a) else {
                continue;
            };
            let xi = i64::from(planes.value(p, false));
            let xq = i64::from(planes.value(p, true));
            let (mi, mq) = if self.format.complex {
                (xi * c + xq * s, xq * c - xi * s)
            } else {
                (xi * c, -xi * s)
            };
            for (sum, t) in sums.iter_mut().zip(code) {
                sum.0 += mi * t;
                sum.1 += mq * t;
            }
        }
    }

    /// The replica's logic chip at block sample `q` (may be before the block) for the span
    /// starting at block sample `start`: the code phase of `q`'s word start extrapolated from
    /// the NCO, then the byte-table definition.
    fn code_bit(&self, start: usize, q: i64) -> u8 {
        let w = q.div_euclid(WORD_SAMPLES as i64);
        let k = q.rem_euclid(WORD_SAMPLES as i64) as usize;
        let offset = i128::from(w * WORD_SAMPLES as i64 - start as i64);
        let phase = (i128::from(self.code.phase) + offset * i128::from(self.code.step))
            .rem_euclid(i128::from(CODE_WRAP)) as u64;
        replica_chip(self.prn, phase, self.code.step, self.table_step, k)
    }
}
