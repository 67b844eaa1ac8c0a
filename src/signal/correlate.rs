//! One interface for the two correlators: [`Correlate`], implemented by the `i8`
//! [`Correlator`] and the bit-parallel [`BitCorrelator`], so that tracking
//! ([`Channel`](crate::tracking::Channel)), the acquisition hand-over and
//! [`SampleReceiver`](crate::receiver::SampleReceiver) do not care which one runs: the choice
//! follows the sample format (decoded `i8` samples in a [`SampleBlock`], or 1- and 2-bit bit
//! planes in a [`BitBlock`]).
//!
//! | correlator | block it reads | front-end settings ([`Correlate::Settings`]) | tap scale |
//! |---|---|---|---|
//! | [`Correlator`] | [`SampleBlock`] (`i8`) | `()` | `127 · Σ x·e^{−jφ}·T`, `x` in `i8` units |
//! | [`BitCorrelator`] | [`BitBlock`] (planes + code table) | [`BitSettings`] (plane format, carrier levels) | `Σ x_q·r*·T`, `x_q ∈ {±1, ±3}` |
//!
//! Everything downstream of the taps uses ratios (discriminators, C/N0, phase-lock indicator,
//! the adapter's noise normalization), so the scales never meet; the one absolute figure, the
//! noise tap's floor below which a reading is the samples' rounding rather than thermal noise,
//! comes from the correlator ([`Correlate::rounding_noise_per_sample`]).

use super::bitwise::{
    BitBlock, BitCorrelator, BitCorrelatorConfig, BitCorrelatorError, BitScratch,
};
use super::bitwise::{CarrierLevels, PlaneFormat};
use super::ca_code::Prn;
use super::correlator::{Correlator, CorrelatorConfig, EpochCorrelations};
use super::nco::{CarrierNco, CodeNco, CARRIER_AMPLITUDE};
use super::{SampleBlock, SignalError};
use crate::tracking::TrackingError;

/// What a correlator needs to know of the block it reads: its length, time stamp, whether
/// its samples are complex, and how to cut it short (the receiver runs its channels one
/// epoch's slice at a time).
pub trait CorrelationBlock: Sized {
    /// Sample instants in the block.
    fn len(&self) -> usize;

    /// Whether the block holds no samples.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Receiver sample index of the block's first sample.
    fn first_sample(&self) -> u64;

    /// Whether the samples are complex (I/Q) rather than real IF.
    fn is_complex(&self) -> bool;

    /// The block's first `n` samples (`None` for `n` beyond its length).
    fn head(&self, n: usize) -> Option<Self>;
}

/// A correlator of one satellite over `A` antennas, with one carrier NCO and one code NCO
/// shared by the antennas: the interface tracking needs. Both implementations have the same
/// semantics (see [`Correlator`]): [`run`](Self::run) stops at the end of each code period,
/// whatever the block boundaries, and returns that period's [`EpochCorrelations`].
pub trait Correlate<const A: usize>: Clone + core::fmt::Debug {
    /// The block of samples this correlator reads.
    type Block<'a>: CorrelationBlock;
    /// The front-end settings beyond the [`CorrelatorConfig`] (`()` for the `i8`
    /// correlator).
    type Settings: Copy + core::fmt::Debug + PartialEq;
    /// The error of the configuration, the NCO setters and [`run`](Self::run); tracking keeps
    /// it as the cause of its own error.
    type Error: Copy + core::fmt::Debug + Into<TrackingError>;
    /// Working memory of [`run_in`](Self::run_in), shared by correlators that run in turn
    /// (`()` for the `i8` correlator, a [`BitScratch`] of 3.3 KB for the bit-parallel one).
    type Scratch: Default + core::fmt::Debug;

    /// A correlator for `prn` with the NCOs at zero phase, the configured IF and the nominal
    /// code rate.
    ///
    /// # Errors
    /// The configuration or settings refused.
    fn new(
        prn: Prn,
        config: &CorrelatorConfig,
        settings: &Self::Settings,
    ) -> Result<Self, Self::Error>;

    /// The satellite.
    fn prn(&self) -> Prn;

    /// Sample rate, Hz.
    fn sample_rate_hz(&self) -> f64;

    /// The carrier NCO.
    fn carrier(&self) -> CarrierNco;

    /// The code NCO.
    fn code(&self) -> CodeNco;

    /// The early/late offset, samples.
    fn early_late_offset_samples(&self) -> usize;

    /// Total carrier phase of the replica now, 2⁻³² cycle.
    fn carrier_phase_total(&self) -> i64;

    /// Sets the carrier NCO frequency (IF + Doppler), Hz.
    ///
    /// # Errors
    /// Non-finite, or `|f| ≥ f_s/2`.
    fn set_carrier_frequency(&mut self, frequency_hz: f64) -> Result<(), Self::Error>;

    /// Sets the code rate, chips/s.
    ///
    /// # Errors
    /// Non-finite, or more than 1 % off the nominal chip rate.
    fn set_code_rate(&mut self, chips_per_second: f64) -> Result<(), Self::Error>;

    /// Sets both NCO steps from their words (from an [`NcoSteering`](super::nco::NcoSteering)):
    /// the tracking loops' setter, integer only.
    ///
    /// # Errors
    /// A code step the correlator cannot run (below [`MIN_CODE_STEP`](super::nco::MIN_CODE_STEP),
    /// or beyond the bit-parallel code table's reach); the correlator is then unchanged.
    fn set_nco_steps(&mut self, carrier_step: u32, code_step: u64) -> Result<(), Self::Error>;

    /// Sets the prompt code phase, chips (modulo 1023), discarding the integration in
    /// progress.
    ///
    /// # Errors
    /// Non-finite.
    fn set_code_phase(&mut self, chips: f64) -> Result<(), Self::Error>;

    /// Sets the carrier NCO phase, cycles, keeping the whole-cycle count.
    ///
    /// # Errors
    /// Non-finite.
    fn set_carrier_phase(&mut self, cycles: f64) -> Result<(), Self::Error>;

    /// Discards the integration in progress; the next output is marked partial.
    fn reset_integration(&mut self);

    /// Correlates `block` from `*cursor` to the end of the block or of the current code
    /// period, advancing `*cursor`; the period's correlations when it completed.
    ///
    /// `scratch` holds nothing between calls: one serves every correlator of a receiver.
    ///
    /// # Errors
    /// A cursor beyond the block, or a block this correlator cannot read; the correlator is
    /// then unchanged.
    fn run_in(
        &mut self,
        block: &Self::Block<'_>,
        cursor: &mut usize,
        scratch: &mut Self::Scratch,
    ) -> Result<Option<EpochCorrelations<A>>, Self::Error>;

    /// [`run_in`](Self::run_in) with a scratch made for this call.
    ///
    /// # Errors
    /// As [`run_in`](Self::run_in).
    fn run(
        &mut self,
        block: &Self::Block<'_>,
        cursor: &mut usize,
    ) -> Result<Option<EpochCorrelations<A>>, Self::Error> {
        self.run_in(block, cursor, &mut Self::Scratch::default())
    }

    /// The noise tap's power per sample (`|N|²`, in the taps' units) that the samples' rounding
    /// alone leaves (`complex`: I/Q samples): the floor below which a noise reading is not
    /// thermal noise ([`crate::tracking::cn0`]).
    fn rounding_noise_per_sample(&self, complex: bool) -> f32;
}

impl<const A: usize> CorrelationBlock for SampleBlock<'_, A> {
    fn len(&self) -> usize {
        SampleBlock::len(self)
    }

    fn first_sample(&self) -> u64 {
        SampleBlock::first_sample(self)
    }

    fn is_complex(&self) -> bool {
        SampleBlock::is_complex(self)
    }

    fn head(&self, n: usize) -> Option<Self> {
        SampleBlock::head(self, n)
    }
}

impl<const A: usize> CorrelationBlock for BitBlock<'_, A> {
    fn len(&self) -> usize {
        BitBlock::len(self)
    }

    fn first_sample(&self) -> u64 {
        BitBlock::first_sample(self)
    }

    fn is_complex(&self) -> bool {
        self.format().complex
    }

    fn head(&self, n: usize) -> Option<Self> {
        BitBlock::head(self, n)
    }
}

/// Uniform rounding noise per component and sample of integer samples, LSB².
const ROUNDING_NOISE_LSB2: f32 = 1.0 / 12.0;

impl<const A: usize> Correlate<A> for Correlator<A> {
    type Block<'a> = SampleBlock<'a, A>;
    type Settings = ();
    type Error = SignalError;
    type Scratch = ();

    fn new(prn: Prn, config: &CorrelatorConfig, _: &()) -> Result<Self, SignalError> {
        Self::new(prn, config)
    }

    fn prn(&self) -> Prn {
        Self::prn(self)
    }

    fn sample_rate_hz(&self) -> f64 {
        Self::sample_rate_hz(self)
    }

    fn carrier(&self) -> CarrierNco {
        Self::carrier(self)
    }

    fn code(&self) -> CodeNco {
        Self::code(self)
    }

    fn early_late_offset_samples(&self) -> usize {
        Self::early_late_offset_samples(self)
    }

    fn carrier_phase_total(&self) -> i64 {
        Self::carrier_phase_total(self)
    }

    fn set_carrier_frequency(&mut self, frequency_hz: f64) -> Result<(), SignalError> {
        Self::set_carrier_frequency(self, frequency_hz)
    }

    fn set_code_rate(&mut self, chips_per_second: f64) -> Result<(), SignalError> {
        Self::set_code_rate(self, chips_per_second)
    }

    fn set_nco_steps(&mut self, carrier_step: u32, code_step: u64) -> Result<(), SignalError> {
        Self::set_nco_steps(self, carrier_step, code_step)
    }

    fn set_code_phase(&mut self, chips: f64) -> Result<(), SignalError> {
        Self::set_code_phase(self, chips)
    }

    fn set_carrier_phase(&mut self, cycles: f64) -> Result<(), SignalError> {
        Self::set_carrier_phase(self, cycles)
    }

    fn reset_integration(&mut self) {
        Self::reset_integration(self);
    }

    fn run_in(
        &mut self,
        block: &SampleBlock<'_, A>,
        cursor: &mut usize,
        (): &mut (),
    ) -> Result<Option<EpochCorrelations<A>>, SignalError> {
        Self::run(self, block, cursor)
    }

    /// `127² · c / 12`: the `i8` samples' rounding (1/12 LSB² per component) through the
    /// carrier table's amplitude (`c` = 2 components for complex samples, 1 for real).
    fn rounding_noise_per_sample(&self, complex: bool) -> f32 {
        let amplitude = f32::from(CARRIER_AMPLITUDE);
        let components = if complex { 2.0 } else { 1.0 };
        amplitude * amplitude * components * ROUNDING_NOISE_LSB2
    }
}

/// The bit-parallel correlator's front-end settings: what the planes hold and how the
/// carrier replica is quantized (with the [`CorrelatorConfig`]: a [`BitCorrelatorConfig`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitSettings {
    /// The planes the blocks carry (1- or 2-bit, complex or real).
    pub format: PlaneFormat,
    /// Quantization of the carrier replica.
    pub carrier: CarrierLevels,
}

impl<const A: usize, const KERNELS: u8> Correlate<A> for BitCorrelator<A, KERNELS> {
    type Block<'a> = BitBlock<'a, A>;
    type Settings = BitSettings;
    type Error = BitCorrelatorError;
    type Scratch = BitScratch;

    fn new(
        prn: Prn,
        config: &CorrelatorConfig,
        settings: &BitSettings,
    ) -> Result<Self, BitCorrelatorError> {
        let config = BitCorrelatorConfig {
            correlator: *config,
            format: settings.format,
            carrier: settings.carrier,
        };
        Self::new(prn, &config)
    }

    fn prn(&self) -> Prn {
        Self::prn(self)
    }

    fn sample_rate_hz(&self) -> f64 {
        Self::sample_rate_hz(self)
    }

    fn carrier(&self) -> CarrierNco {
        Self::carrier(self)
    }

    fn code(&self) -> CodeNco {
        Self::code(self)
    }

    fn early_late_offset_samples(&self) -> usize {
        Self::early_late_offset_samples(self)
    }

    fn carrier_phase_total(&self) -> i64 {
        Self::carrier_phase_total(self)
    }

    fn set_carrier_frequency(&mut self, frequency_hz: f64) -> Result<(), BitCorrelatorError> {
        Self::set_carrier_frequency(self, frequency_hz)
    }

    fn set_code_rate(&mut self, chips_per_second: f64) -> Result<(), BitCorrelatorError> {
        Self::set_code_rate(self, chips_per_second)
    }

    fn set_nco_steps(
        &mut self,
        carrier_step: u32,
        code_step: u64,
    ) -> Result<(), BitCorrelatorError> {
        Self::set_nco_steps(self, carrier_step, code_step)
    }

    fn set_code_phase(&mut self, chips: f64) -> Result<(), BitCorrelatorError> {
        Self::set_code_phase(self, chips)
    }

    fn set_carrier_phase(&mut self, cycles: f64) -> Result<(), BitCorrelatorError> {
        Self::set_carrier_phase(self, cycles)
    }

    fn reset_integration(&mut self) {
        Self::reset_integration(self);
    }

    fn run_in(
        &mut self,
        block: &BitBlock<'_, A>,
        cursor: &mut usize,
        scratch: &mut BitScratch,
    ) -> Result<Option<EpochCorrelations<A>>, BitCorrelatorError> {
        Self::run_in(self, block, cursor, scratch)
    }

    /// The samples are odd integers (`±1`, `±3`: a step of 2, so `4/12` per component of
    /// rounding) times the carrier replica's mean power `E(c² + s²)` (2 for the 2-level
    /// carrier, 1.5 for the 3-level one with a quarter of zeros per component), per sample
    /// component. (A 1-bit signal's noise tap reads 3 times this whatever the input: such
    /// samples are never flagged as rounding-limited.)
    fn rounding_noise_per_sample(&self, complex: bool) -> f32 {
        let replica = match self.carrier_levels() {
            CarrierLevels::Two => 2.0,
            CarrierLevels::Three => 1.5,
        };
        let components = if complex { 2.0 } else { 1.0 };
        4.0 * ROUNDING_NOISE_LSB2 * replica * components
    }
}
