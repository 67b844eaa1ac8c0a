//! Cancellation of known satellites (detected or tracked) from the samples before a search:
//! the second look at a PRN whose first search was masked by stronger satellites.
//!
//! A strong satellite puts its cross-correlation into every other PRN's search: the cells of
//! the background rise (a weaker satellite's peak over their mean falls), they repeat every
//! millisecond (the threshold rises with the background's spread), and where the codes
//! cross-correlate strongly a peak stands out that the cross-correlation test must weigh
//! against a real satellite's. Removing the strong satellites from the samples removes all
//! three: for each known signal `j` (code phase `τ_j`, Doppler `f_j`, both refined on the
//! samples first) the phasor of millisecond `m` is the least-squares amplitude
//! `a_jm = c · mean_k (x_k c_j(k) e^{−jθ_j(k)})` (`c` = 1 for complex samples, 2 for real
//! ones), and `a_jm c_j(k) e^{jθ_j(k)}` (its real part for real samples) is subtracted from
//! every sample of millisecond `m` before the integrate-and-dump. The phasor is measured
//! again for each millisecond mixed (no storage, data bits and carrier phase followed; one
//! more pass over the millisecond's samples per signal).
//!
//! # Refinement
//! The search locates a peak to a fraction of a code bin and of a Doppler bin; a replica off
//! by `δ` chips leaves `2δ` of the signal's power behind. Each signal's code phase is refined
//! on the first [`REFINE_MS`] ms by the correlation power at offsets of
//! [`REFINE_STEP_CHIPS`] within ±half a chip (parabola through the best and its neighbours),
//! then its Doppler by the phase progression of the squared millisecond phasors (squared:
//! a data-bit flip does not turn them; unambiguous within ±250 Hz).

use super::{Acquisition, AcquisitionConfig, KnownSignal, SearchSamples};
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ, GPS_L1_HZ};
use crate::signal::nco::{
    carrier_index, CarrierNco, CodeNco, CARRIER_AMPLITUDE, CODE_WRAP, COS_TABLE, SIN_TABLE,
};
use crate::tracking::fft::Complex;

/// Most signals cancelled from one search (the strongest first).
pub const MAX_CANCELLED: usize = 16;

/// Milliseconds of the samples that refine a cancelled signal's code phase and Doppler.
pub const REFINE_MS: usize = 8;

/// Code-phase step of the refinement, chips (±4 steps: ±half a chip).
pub const REFINE_STEP_CHIPS: f64 = 0.125;

/// Refinement offsets either side of the search's code phase.
const REFINE_OFFSETS: i32 = 4;

/// One signal to cancel: its carrier (IF included) and code NCO words.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(super) struct Cancelled {
    prn: Prn,
    /// Carrier NCO step (IF plus Doppler), 2⁻³² cycle per sample.
    carrier_step: u32,
    /// Code phase at sample 0, chips.
    chips: f64,
    /// Code rate, chips per sample.
    chips_per_sample: f64,
    /// Code phase step, 2⁻³² chip per sample.
    code_step: u64,
}

impl Default for Cancelled {
    fn default() -> Self {
        Self::NONE
    }
}

impl Cancelled {
    /// No signal (the engine's empty slots).
    pub(super) const NONE: Self = Self {
        prn: Prn::FIRST,
        carrier_step: 0,
        chips: 0.0,
        chips_per_sample: 0.0,
        code_step: 0,
    };

    /// The signal at code phase `chips` (at sample 0) and Doppler `doppler_hz`.
    fn new(prn: Prn, chips: f64, doppler_hz: f64, config: &AcquisitionConfig) -> Self {
        let fs = config.sample_rate_hz;
        let rate = CA_CHIP_RATE_HZ * (1.0 + doppler_hz / GPS_L1_HZ);
        Self {
            prn,
            carrier_step: CarrierNco::step_for(config.intermediate_frequency_hz + doppler_hz, fs),
            chips,
            chips_per_sample: rate / fs,
            code_step: CodeNco::step_for(rate, fs),
        }
    }

    /// The replica's carrier and code phase words at sample `k`.
    pub(super) fn at(&self, k: usize) -> (u32, u64) {
        let carrier = self.carrier_step.wrapping_mul(k as u32);
        let code = CodeNco::phase_for(self.chips + k as f64 * self.chips_per_sample);
        (carrier, code)
    }

    /// The replica's chip sign at code phase word `code`.
    #[inline(always)]
    pub(super) fn chip(&self, code: u64) -> f32 {
        // (the packed bits, not the 32 KiB sign table: a firmware that never runs the `i8`
        // correlator links neither; `code < CODE_WRAP`, so the chip is below 1023)
        f32::from(self.prn.chip((code >> 32) as usize))
    }

    /// Advances the phase words by one sample.
    #[inline(always)]
    pub(super) fn step(&self, carrier: &mut u32, code: &mut u64) {
        *carrier = carrier.wrapping_add(self.carrier_step);
        // (both below CODE_WRAP, far from u64::MAX: the sum cannot wrap)
        *code = code.wrapping_add(self.code_step);
        if *code >= CODE_WRAP {
            *code -= CODE_WRAP;
        }
    }

    /// The signal's phasor over millisecond `m`: least squares on the samples less `dc`
    /// (phase from sample 0), sample units.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub(super) fn phasor(
        &self,
        m: usize,
        samples: SearchSamples<'_>,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> Complex {
        let gain = if samples.is_complex() { 1.0 } else { 2.0 };
        let dq = if samples.is_complex() { dc[1] } else { 0.0 };
        let (start, end) = (
            config.ms_start(m),
            config.ms_start(m.saturating_add(1)).min(samples.len()),
        );
        let (mut carrier, mut code) = self.at(start);
        let (mut sr, mut si) = (0.0f32, 0.0f32);
        samples.for_each_centred(start..end, [dc[0], dq], |x, y| {
            let c = self.chip(code);
            let idx = carrier_index(carrier);
            let (cs, sn) = (f32::from(COS_TABLE[idx]) * c, f32::from(SIN_TABLE[idx]) * c);
            sr += x * cs + y * sn;
            si += y * cs - x * sn;
            self.step(&mut carrier, &mut code);
        });
        let n = end.saturating_sub(start).max(1) as f32 * f32::from(CARRIER_AMPLITUDE);
        [gain * sr / n, gain * si / n]
    }
}

/// The signal `s` with its code phase and Doppler refined on the first [`REFINE_MS`] ms of
/// the samples (see the module documentation).
#[cfg_attr(feature = "optimize-cold", optimize(size))]
fn refined(
    s: &KnownSignal,
    samples: SearchSamples<'_>,
    config: &AcquisitionConfig,
    dc: [f32; 2],
) -> Cancelled {
    let ms = REFINE_MS.min(usize::from(config.noncoherent_ms)).max(1);
    let doppler = f64::from(s.doppler_hz);
    let power_at = |chips: f64, doppler: f64| {
        let c = Cancelled::new(s.prn, chips, doppler, config);
        (0..ms)
            .map(|m| {
                let a = c.phasor(m, samples, config, dc);
                a[0] * a[0] + a[1] * a[1]
            })
            .sum::<f32>()
    };
    let (mut best, mut best_k, mut idx, mut powers) = (f32::MIN, 0i32, 0usize, [0.0f32; 9]);
    let slots = 0..powers.len();
    for ((j, slot), k) in slots
        .zip(powers.iter_mut())
        .zip(-REFINE_OFFSETS..=REFINE_OFFSETS)
    {
        let p = power_at(
            s.code_phase_chips + f64::from(k) * REFINE_STEP_CHIPS,
            doppler,
        );
        *slot = p;
        if p > best {
            (best, best_k, idx) = (p, k, j);
        }
    }
    // Parabola through the amplitudes of the best offset and its neighbours.
    let amp = |j: usize| powers.get(j).map_or(0.0, |p| crate::sqrtf(p.max(0.0)));
    let (am, a0, ap) = (
        amp(idx.wrapping_sub(1)),
        amp(idx),
        amp(idx.saturating_add(1)),
    );
    let curv = 2.0 * a0 - am - ap;
    let delta = if curv > 0.0 && idx > 0 && idx.saturating_add(1) < powers.len() {
        (0.5 * (ap - am) / curv).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    let chips = s.code_phase_chips + (f64::from(best_k) + f64::from(delta)) * REFINE_STEP_CHIPS;
    // Doppler from the squared phasors' progression (a bit flip does not turn a square).
    let c = Cancelled::new(s.prn, chips, doppler, config);
    let square = |a: Complex| [a[0] * a[0] - a[1] * a[1], 2.0 * a[0] * a[1]];
    let mut turn = [0.0f64; 2];
    let mut previous = square(c.phasor(0, samples, config, dc));
    for m in 1..ms {
        let a = square(c.phasor(m, samples, config, dc));
        turn[0] += f64::from(a[0] * previous[0] + a[1] * previous[1]);
        turn[1] += f64::from(a[1] * previous[0] - a[0] * previous[1]);
        previous = a;
    }
    let df = if turn[0] != 0.0 || turn[1] != 0.0 {
        libm::atan2(turn[1], turn[0]) / core::f64::consts::TAU * 500.0
    } else {
        0.0
    };
    Cancelled::new(s.prn, chips, doppler + df, config)
}

impl<const N: usize, const L: usize> Acquisition<N, L> {
    /// Sets the signals cancelled from the samples in the scans that follow (until the next
    /// [`Acquisition::prepare_interference`]): `signals` except those of `prn`, at most
    /// [`MAX_CANCELLED`], each refined on the samples. Returns how many.
    pub(super) fn set_cancellation(
        &mut self,
        prn: Prn,
        signals: &[KnownSignal],
        samples: SearchSamples<'_>,
        config: &AcquisitionConfig,
        dc: [f32; 2],
    ) -> usize {
        self.cancelled_count = 0;
        let mut count = 0usize;
        let others = signals.iter().filter(|s| s.prn != prn);
        for (slot, s) in self.cancelled.iter_mut().zip(others) {
            *slot = refined(s, samples, config, dc);
            count = count.saturating_add(1);
        }
        self.cancelled_count = count;
        count
    }
}
