//! [`SampleReceiver`]: the whole receiver from raw samples, for a software front half: the
//! acquisition engine, up to `S` tracking channels over the three antennas, the
//! [`ObservationAdapter`] and [`EpochClock`] that turn their epochs into observations, and the
//! [`AttitudeReceiver`] they feed, in one object.
//!
//! ```text
//!  samples (3 antennas) ──► search(prn) ──► Acquisition<N> ──► detected: a Channel<3> starts
//!          │
//!          └──► push_samples(block) ──► every channel, 1 ms slices, round robin
//!                     ──► ObservationAdapter (noise floor, lock gating) ──► EpochClock (epoch k)
//!                     ──► AttitudeReceiver::push_observation(k) ──► attitude()
//! ```
//!
//! The caller owns the sample buffers, the search schedule (which PRNs, when: with an almanac
//! and an orbit, the ones predicted above the mask) and the navigation aiding and gyro
//! ([`SampleReceiver::receiver_mut`]). The channels run one 1 ms slice at a time in turn, so
//! the observations reach the receiver in epoch order whatever the block size.
//!
//! On a microcontroller `push_samples` is the 1 ms path (the DMA block's interrupt, say): its
//! occasional heavy work can wait for the main loop. The attitude receiver's block and window
//! stages ([`AttitudeReceiver::set_deferred_stages`]) and the channels' cross-correlation
//! checks ([`SampleReceiver::set_deferred_checks`]) then run in
//! [`SampleReceiver::run_deferred`]; work still waiting when the next block comes runs then,
//! counted.
//!
//! The channels run the correlator `C` ([`Correlate`]), and [`SampleReceiver::push_samples`]
//! takes its block: decoded `i8` samples ([`SampleBlock`](crate::signal::SampleBlock)) for
//! the default [`Correlator`], bit planes ([`BitBlock`](crate::signal::bitwise::BitBlock),
//! packed from the front end's bytes by
//! [`PlaneBuffer::pack_bytes`](crate::signal::bitwise::PlaneBuffer::pack_bytes)) for the
//! bit-parallel correlator ([`SampleReceiver::with_settings`]). The search reads the
//! reference antenna's samples decoded ([`SampleReceiver::search`]) or as bit planes
//! ([`SampleReceiver::search_samples`] with
//! [`SearchSamples::Planes`], collected block by block
//! with [`PlaneBuffer::append`](crate::signal::bitwise::PlaneBuffer::append)): the 13 ms of a
//! 6 ms search and its dwell at 2.6 Msps take 61 KiB as `i8`, 7.6 / 15.2 KiB as 1- / 2-bit
//! complex planes.

use heapless::Vec;

use super::config::ConfigError;
use super::{AttitudeReceiver, ReceiverAttitude, ReceiverConfig};
use crate::receiver::ReceiverError;
use crate::receiver::{AdapterConfig, EpochClock, ObservationAdapter};
use crate::signal::{Correlate, CorrelationBlock, Correlator, Prn};
use crate::tracking::acquisition::{
    SearchSamples, CANCELLATION_KEEP_FRACTION, CROSS_CORRELATION_MARGIN,
};
use crate::tracking::xcorr::SignalProbe;
use crate::tracking::{
    Acquisition, AcquisitionConfig, Channel, ChannelConfig, ChannelState, KnownSignal,
    SearchResult, TrackingEpoch,
};

/// What a [`SampleReceiver`] needs besides the [`ReceiverConfig`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SampleFrontConfig {
    /// The acquisition search (sample rate, IF, Doppler span, non-coherent sums, false-alarm
    /// probability).
    pub acquisition: AcquisitionConfig,
    /// The tracking channels ([`ChannelConfig::leo`] in orbit).
    pub channel: ChannelConfig,
    /// Noise normalization and lock gating of the channels' epochs.
    pub adapter: AdapterConfig,
    /// Receiver sample at the centre of receiver epoch 0 (half an epoch for a grid that
    /// starts with the samples).
    pub epoch_origin_sample: u64,
    /// Samples per receiver epoch (the receiver's epoch times the sample rate: 2600 for 1 ms
    /// at 2.6 Msps).
    pub samples_per_epoch: u32,
    /// A channel without a locked epoch for this many samples is closed (the satellite set,
    /// or the hand-over failed); its PRN can be searched again.
    pub release_after_samples: u64,
}

impl SampleFrontConfig {
    /// Complex samples at `sample_rate_hz` (zero IF), LEO channels, a ±50 kHz search over
    /// 20 ms, 1 ms epochs from sample 0, channels closed after 2 s without lock.
    pub fn leo_complex(sample_rate_hz: f64) -> Self {
        Self {
            acquisition: AcquisitionConfig {
                sample_rate_hz,
                intermediate_frequency_hz: 0.0,
                doppler_max_hz: 50_000.0,
                doppler_step_hz: 500.0,
                noncoherent_ms: 20,
                false_alarm_probability: 1e-5,
            },
            channel: ChannelConfig::leo(sample_rate_hz, 0.0),
            adapter: AdapterConfig::default(),
            epoch_origin_sample: (sample_rate_hz * 0.5e-3) as u64,
            samples_per_epoch: (sample_rate_hz * 1e-3) as u32,
            release_after_samples: (2.0 * sample_rate_hz) as u64,
        }
    }
}

/// What one channel of a [`SampleReceiver`] is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelStatus {
    /// The satellite.
    pub prn: Prn,
    /// Channel state after its last epoch.
    pub state: ChannelState,
    /// Its last C/N0 estimate, dB-Hz.
    pub cn0_dbhz: f32,
    /// Its last epoch had code and phase lock while tracking.
    pub locked: bool,
    /// Receiver sample of its last locked epoch (the hand-over's first sample before one).
    pub last_lock_sample: u64,
}

/// What one [`SampleReceiver::push_samples`] call did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SampleReport {
    /// Complete tracking epochs (all channels).
    pub epochs: u32,
    /// Observations the receiver accepted.
    pub observations: u32,
    /// Observations refused because the satellite has no aiding yet.
    pub without_aiding: u32,
    /// Observations refused because their epoch was already closed (should stay 0).
    pub late: u32,
    /// Channels closed (for lack of lock, or as cross-correlations).
    pub released: u8,
    /// Of those, channels that released themselves as another satellite's
    /// cross-correlation.
    pub cross_correlations: u8,
}

/// The receiver from raw samples: acquisition engine (`N`-point FFT), up to `S` channels on
/// the correlator `C` (the `i8` [`Correlator`] by default, the bit-parallel
/// [`BitCorrelator`](crate::signal::bitwise::BitCorrelator) for 1- and 2-bit front ends,
/// made by [`SampleReceiver::with_settings`]), adapter, epoch clock and the
/// [`AttitudeReceiver`].
#[derive(Clone, Debug)]
pub struct SampleReceiver<const S: usize, const N: usize, C: Correlate<3> = Correlator<3>> {
    config: SampleFrontConfig,
    /// The channels' correlator settings.
    settings: C::Settings,
    acquisition: Acquisition<N>,
    channels: Vec<(Channel<3, C>, ChannelStatus), S>,
    /// The channels' correlator working memory, one for all ([`Correlate::run_in`]).
    scratch: C::Scratch,
    adapter: ObservationAdapter,
    clock: EpochClock,
    receiver: AttitudeReceiver,
    /// First sample the channels have not seen.
    frontier: Option<u64>,
    /// The channels' cross-correlation checks wait for [`Self::run_deferred`].
    deferred_checks: bool,
    /// A check is waiting (deferred mode).
    checks_waiting: bool,
    /// Checks that were still waiting when the next block came, and ran then.
    check_overruns: u32,
}

impl<const S: usize, const N: usize> SampleReceiver<S, N> {
    /// A receiver with no channels, on the `i8` correlator.
    ///
    /// # Errors
    /// [`ReceiverError::InvalidConfig`] for an invalid receiver, acquisition, channel or
    /// adapter configuration, zero samples per epoch, or an FFT size `N` outside 1024–8192.
    pub fn new(receiver: ReceiverConfig, config: SampleFrontConfig) -> Result<Self, ReceiverError> {
        Self::with_settings(receiver, config, ())
    }
}

impl<const S: usize, const N: usize, C: Correlate<3>> SampleReceiver<S, N, C> {
    /// A receiver with no channels, whose channels run the correlator `C` with the front-end
    /// `settings` (a [`BitSettings`](crate::signal::BitSettings) for bit planes). The
    /// acquisition engine's FFT tables are built by the first [`Self::search`] (about 1000
    /// `f64` sines and cosines: software on the M4F), so that construction keeps no second
    /// copy of the engine on the stack.
    ///
    /// # Errors
    /// As [`SampleReceiver::new`]; also for settings the correlator refuses.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn with_settings(
        receiver: ReceiverConfig,
        config: SampleFrontConfig,
        settings: C::Settings,
    ) -> Result<Self, ReceiverError> {
        // The engine's 40 KB are made in place, blank, and built by the first search: a
        // built engine returned by value would leave a copy in this frame (on a
        // microcontroller's stack, beside the receiver being returned).
        Acquisition::<N>::check_size().map_err(ConfigError::from)?;
        // the channel configuration is validated by a trial channel
        Channel::<3, C>::with_settings(Prn::FIRST, &config.channel, &settings)
            .map_err(ConfigError::from)?;
        let adapter = ObservationAdapter::new(config.adapter).map_err(ConfigError::Adapter)?;
        let clock = EpochClock::new(config.epoch_origin_sample, config.samples_per_epoch)
            .map_err(ConfigError::Adapter)?;
        let receiver = AttitudeReceiver::new(receiver)?;
        Ok(Self::assemble(settings, adapter, clock, receiver, config))
    }

    /// The receiver of validated parts, channels none, the acquisition engine blank. Out of
    /// line, so that the caller's `Ok` takes the value where it is made (the engine's 40 KB
    /// are not built in one frame and copied to another).
    #[inline(never)]
    fn assemble(
        settings: C::Settings,
        adapter: ObservationAdapter,
        clock: EpochClock,
        receiver: AttitudeReceiver,
        config: SampleFrontConfig,
    ) -> Self {
        Self {
            settings,
            adapter,
            clock,
            receiver,
            config,
            acquisition: Acquisition::blank(),
            channels: Vec::new(),
            scratch: C::Scratch::default(),
            frontier: None,
            deferred_checks: false,
            checks_waiting: false,
            check_overruns: 0,
        }
    }

    /// The attitude receiver (estimates, health, events).
    pub fn receiver(&self) -> &AttitudeReceiver {
        &self.receiver
    }

    /// The attitude receiver, for the aiding and the gyro (and observations from elsewhere).
    pub fn receiver_mut(&mut self) -> &mut AttitudeReceiver {
        &mut self.receiver
    }

    /// The receiver's attitude ([`AttitudeReceiver::attitude`]).
    pub fn attitude(&self) -> ReceiverAttitude {
        self.receiver.attitude()
    }

    /// The channels' status, in the order they were started.
    pub fn channels(&self) -> impl Iterator<Item = &ChannelStatus> {
        self.channels.iter().map(|(_, s)| s)
    }

    /// Whether a channel tracks `prn`.
    pub fn tracks(&self, prn: Prn) -> bool {
        self.channels.iter().any(|(_, s)| s.prn == prn)
    }

    /// Searches `prn` in the reference antenna's samples `i` (and `q` for complex samples)
    /// whose first sample is receiver sample `first_sample`
    /// ([`AcquisitionConfig::samples_needed`] of them: the search and its verification
    /// dwell); a detection that the channels' satellites do not explain as their
    /// cross-correlation ([`Acquisition::cross_check`]; `detected` is then false) starts a
    /// channel that tracks from the first sample of the next [`Self::push_samples`] block.
    /// When the channels' satellites masked the search (their cross-correlation in its
    /// background, or its detection explained as one), the PRN is searched again with them
    /// cancelled ([`Acquisition::search_report_cancelling`]), and that search's detection,
    /// if it keeps its power with them cancelled, is the result.
    /// Searching a PRN that already has a channel only reports.
    ///
    /// # Errors
    /// [`ReceiverError::Acquisition`] for samples or a configuration the search refuses;
    /// [`ReceiverError::TooManySatellites`] for a detection with all `S` channels busy (the
    /// result is lost; close one first).
    pub fn search(
        &mut self,
        prn: Prn,
        i: &[i8],
        q: Option<&[i8]>,
        first_sample: u64,
    ) -> Result<SearchResult, ReceiverError> {
        let samples = SearchSamples::decoded(i, q)?;
        self.search_samples(prn, samples, first_sample)
    }

    /// [`Self::search`] on `samples`: decoded, or the bit planes of a 1- or 2-bit front end
    /// (a microcontroller keeps the search's milliseconds packed: 8 to 16 times less memory
    /// than `i8`).
    ///
    /// # Errors
    /// As [`Self::search`].
    pub fn search_samples(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        first_sample: u64,
    ) -> Result<SearchResult, ReceiverError> {
        self.search_samples_near(prn, samples, first_sample, 0.0)
    }

    /// [`Self::search_samples`] over the configuration's `±doppler_max_hz` about
    /// `predicted_doppler_hz` (a warm start: the Doppler predicted from the almanac, time and
    /// orbit; [`Acquisition::search_report_near`]), the second look included.
    ///
    /// # Errors
    /// As [`Self::search`]; [`ReceiverError::Acquisition`] also for a non-finite prediction
    /// or one beyond [`crate::tracking::acquisition::MAX_DOPPLER_CENTRE_HZ`].
    pub fn search_samples_near(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        first_sample: u64,
        predicted_doppler_hz: f32,
    ) -> Result<SearchResult, ReceiverError> {
        let config = self.config.acquisition;
        // (built at the first search: see `with_settings`)
        self.acquisition.build()?;
        let report = self.acquisition.search_report_near(
            prn,
            samples,
            first_sample,
            &config,
            predicted_doppler_hz,
        )?;
        let mut result = report.result;
        if self.tracks(prn) {
            return Ok(result);
        }
        let mut known: Vec<KnownSignal, S> = Vec::new();
        for k in self
            .channels
            .iter()
            .filter_map(|(c, _)| c.known_signal_at(first_sample))
        {
            // One entry per channel: at most S, the capacity.
            if known.push(k).is_err() {
                break;
            }
        }
        // The channels' satellites' cross-correlation in the background masks a weaker one.
        let mut masked = report.effective_ms < config.noncoherent_ms;
        // (No channel with code lock: nothing could explain it, and the check's direct
        // correlation of the candidate, a sixth of a warm search's cost, is skipped.)
        if result.detected && !known.is_empty() {
            // Not a satellite when the channels' satellites explain it as their
            // cross-correlation.
            let check = self.acquisition.cross_check(
                &result,
                &known,
                samples,
                &config,
                CROSS_CORRELATION_MARGIN,
            )?;
            result.detected = !check.explained;
            masked |= check.explained;
        }
        // (Not when interference was found: it makes a background of its own.)
        if !result.detected && masked && !report.interference && !known.is_empty() {
            let threshold = report.result.threshold;
            result = self
                .second_look(
                    prn,
                    samples,
                    first_sample,
                    &known,
                    threshold,
                    predicted_doppler_hz,
                )?
                .unwrap_or(result);
        }
        if result.detected {
            self.start(&result)?;
        }
        Ok(result)
    }

    /// The search of `prn` again with the channels' signals `known` cancelled from the
    /// samples: its result when it detects a satellite whose metric passes the first
    /// search's `first_threshold` too (the cancellation lowers the background's spread, not a
    /// tone's tail) and that keeps its power with them cancelled
    /// ([`Acquisition::cancellation_check`]), `None` otherwise; about the first search's
    /// `predicted_doppler_hz`.
    fn second_look(
        &mut self,
        prn: Prn,
        samples: SearchSamples<'_>,
        first_sample: u64,
        known: &[KnownSignal],
        first_threshold: f32,
        predicted_doppler_hz: f32,
    ) -> Result<Option<SearchResult>, ReceiverError> {
        let config = self.config.acquisition;
        let again = self.acquisition.search_report_cancelling_near(
            prn,
            samples,
            first_sample,
            &config,
            known,
            predicted_doppler_hz,
        )?;
        if !again.result.detected || !(again.result.metric > first_threshold) {
            return Ok(None);
        }
        let check = self.acquisition.cancellation_check(
            &again.result,
            known,
            samples,
            &config,
            CANCELLATION_KEEP_FRACTION,
        )?;
        Ok(check.kept.then_some(again.result))
    }

    /// Starts a channel from a detection made elsewhere (another engine, a hardware search).
    ///
    /// # Errors
    /// [`ReceiverError::TooManySatellites`] with all `S` channels busy;
    /// [`ReceiverError::Tracking`] for a result the channel refuses.
    pub fn start(&mut self, result: &SearchResult) -> Result<(), ReceiverError> {
        if self.channels.is_full() {
            return Err(ReceiverError::TooManySatellites);
        }
        let mut channel =
            Channel::<3, C>::with_settings(result.prn, &self.config.channel, &self.settings)?;
        channel.start(result)?;
        let status = ChannelStatus {
            prn: result.prn,
            state: channel.state(),
            cn0_dbhz: 0.0,
            locked: false,
            last_lock_sample: self.frontier.unwrap_or(result.first_sample),
        };
        // (checked for room above; the refused channel is dropped)
        self.channels
            .push((channel, status))
            .map_err(|_| ReceiverError::TooManySatellites)
    }

    /// Closes `prn`'s channel; true when there was one.
    pub fn release(&mut self, prn: Prn) -> bool {
        let before = self.channels.len();
        retain(&mut self.channels, |(_, s)| s.prn != prn);
        self.channels.len() < before
    }

    /// Runs every channel over `block` (the stream's next samples of the three antennas), one
    /// receiver epoch of samples at a time in turn, and hands every usable epoch to the
    /// receiver under its epoch; then closes the channels without lock for
    /// [`SampleFrontConfig::release_after_samples`]. Bounded: at most
    /// `block.len() / samples_per_epoch + 1` slices, each at most three epochs per channel.
    ///
    /// # Errors
    /// [`ReceiverError::Tracking`] for a block that does not continue the stream (the
    /// channels are then unusable: release them); [`ReceiverError::NonFinite`] /
    /// [`ReceiverError::InvalidInput`] for an epoch the adapter or the receiver refuses.
    pub fn push_samples(&mut self, block: &C::Block<'_>) -> Result<SampleReport, ReceiverError> {
        self.push_samples_observed(block, &mut |_, _, _| {})
    }

    /// [`Self::push_samples`] that also shows every channel's tracking epoch to `observer`
    /// as it closes (one call per channel and 1 ms code period, in the order the receiver
    /// gets them): the satellite, the epoch (prompt, code phase, Doppler, C/N0, receiver
    /// samples), and whether it had code and phase lock while tracking
    /// ([`ChannelStatus::locked`]). For the navigation message's bit and subframe
    /// synchronization on the prompts ([`crate::nav::ChannelDecoder`]) and pseudoranges from
    /// the code phases. Same bounds and errors as [`Self::push_samples`].
    ///
    /// # Errors
    /// As [`Self::push_samples`].
    pub fn push_samples_observed(
        &mut self,
        block: &C::Block<'_>,
        observer: &mut impl FnMut(Prn, &TrackingEpoch<3>, bool),
    ) -> Result<SampleReport, ReceiverError> {
        let mut report = SampleReport::default();
        let slice = self.config.samples_per_epoch.max(1) as usize;
        // each channel's position in `block`
        let mut cursors = [0usize; S];
        let mut end = 0usize;
        while end < block.len() {
            end = end.saturating_add(slice).min(block.len());
            // the block up to this slice's end, shared by every channel
            let sub = block.head(end).ok_or(ReceiverError::Tracking(
                crate::tracking::TrackingError::Signal(
                    crate::signal::SignalError::CursorOutOfRange,
                ),
            ))?;
            for ((channel, status), cursor) in self.channels.iter_mut().zip(cursors.iter_mut()) {
                // each call stops at a code period's end: at most a few per slice
                for _ in 0..4 {
                    if *cursor >= end {
                        break;
                    }
                    let Some(epoch) = channel.process_in(&sub, cursor, &mut self.scratch)? else {
                        continue;
                    };
                    report.epochs = report.epochs.saturating_add(1);
                    status.state = epoch.state;
                    status.cn0_dbhz = epoch.cn0_dbhz;
                    status.locked = epoch.state == ChannelState::Tracking
                        && epoch.lock.code
                        && epoch.lock.phase;
                    if status.locked {
                        status.last_lock_sample = epoch.correlations.first_sample;
                    }
                    observer(status.prn, &epoch, status.locked);
                    let obs = self
                        .adapter
                        .observe(&epoch, [0.0, 0.0, 1.0])
                        .map_err(ReceiverError::Adapter)?;
                    let (Some(obs), Some(k)) = (obs, self.clock.epoch_of(&epoch.correlations))
                    else {
                        continue;
                    };
                    match self.receiver.push_observation(k, &obs) {
                        Ok(()) => report.observations = report.observations.saturating_add(1),
                        Err(ReceiverError::NoAiding) => {
                            report.without_aiding = report.without_aiding.saturating_add(1);
                        }
                        Err(ReceiverError::StaleEpoch) => {
                            report.late = report.late.saturating_add(1);
                        }
                        Err(e) => return Err(e),
                    }
                }
            }
        }
        let now = block.first_sample().saturating_add(block.len() as u64);
        self.frontier = Some(now);
        report.cross_correlations = self.checks_now_or_deferred();
        report.released = self.release_channels(now);
        Ok(report)
    }

    /// Defers the channels' cross-correlation checks (`deferred` true) out of
    /// [`Self::push_samples`] into [`Self::run_deferred`], as
    /// [`AttitudeReceiver::set_deferred_stages`] defers the block and window stages: the
    /// millisecond that ends the channels' lock windows then only notes that a check is
    /// waiting (each check is a few hundred thousand instructions on the M4F, in one
    /// millisecond). A check still waiting when the next block comes runs then (counted:
    /// [`Self::check_overruns`]). `false` runs a waiting check now.
    pub fn set_deferred_checks(&mut self, deferred: bool) {
        self.deferred_checks = deferred;
        if !deferred {
            self.run_waiting_checks();
        }
    }

    /// Runs what waits for the main loop: the channels' cross-correlation checks
    /// ([`Self::set_deferred_checks`]) and the attitude receiver's stages
    /// ([`AttitudeReceiver::run_deferred`]). The report counts the channels the checks
    /// released (`released`, `cross_correlations`); its other fields are 0.
    pub fn run_deferred(&mut self) -> SampleReport {
        let report = self.run_waiting_checks();
        self.receiver.run_deferred();
        report
    }

    /// The waiting cross-correlation checks, and the channels they release.
    fn run_waiting_checks(&mut self) -> SampleReport {
        let mut report = SampleReport::default();
        if self.checks_waiting {
            self.checks_waiting = false;
            report.cross_correlations = self.check_cross_correlations();
            if report.cross_correlations > 0 {
                let now = self.frontier.unwrap_or(0);
                report.released = self.release_channels(now);
            }
        }
        report
    }

    /// Cross-correlation checks that were still waiting when the next block came.
    pub fn check_overruns(&self) -> u32 {
        self.check_overruns
    }

    /// The end of a block: the channels' checks run now, or wait for [`Self::run_deferred`];
    /// returns how many channels released themselves now.
    fn checks_now_or_deferred(&mut self) -> u8 {
        if self.checks_waiting {
            // the main loop did not run them before this block: now (counted)
            self.check_overruns = self.check_overruns.saturating_add(1);
            self.checks_waiting = false;
            return self.check_cross_correlations();
        }
        if self.deferred_checks {
            self.checks_waiting = self.any_check_pending();
            return 0;
        }
        self.check_cross_correlations()
    }

    /// Closes the channels without a locked epoch for `release_after_samples` before `now`
    /// and those that released themselves as a cross-correlation; returns how many.
    fn release_channels(&mut self, now: u64) -> u8 {
        let limit = self.config.release_after_samples;
        let before = self.channels.len();
        retain(&mut self.channels, |(c, s)| {
            now.saturating_sub(s.last_lock_sample) < limit && !c.is_cross_correlation()
        });
        u8::try_from(before.saturating_sub(self.channels.len())).unwrap_or(u8::MAX)
    }

    /// Whether some channel's cross-correlation test is due.
    fn any_check_pending(&self) -> bool {
        self.channels
            .iter()
            .any(|(c, _)| c.cross_correlation_test_pending())
    }

    /// Every channel's cross-correlation check against the others
    /// ([`Channel::check_cross_correlation`]); returns how many released themselves.
    /// The probes (f64 code phases: soft float on the M4F) are gathered only in the
    /// milliseconds in which some channel's test is due.
    fn check_cross_correlations(&mut self) -> u8 {
        if !self.any_check_pending() {
            return 0;
        }
        let mut probes: Vec<SignalProbe, S> = Vec::new();
        for p in self.channels.iter().filter_map(|(c, _)| c.probe()) {
            // One probe per channel: at most S, the capacity.
            if probes.push(p).is_err() {
                break;
            }
        }
        let mut released = 0u8;
        for (channel, _) in self.channels.iter_mut() {
            if channel.check_cross_correlation(&probes).is_some() {
                released = released.saturating_add(1);
            }
        }
        released
    }
}

/// Keeps the items for which `keep` holds, in order (as `heapless::Vec::retain`, whose
/// counters keep overflow checks the optimizer cannot discharge): a stable in-place
/// compaction by swaps, then the rest dropped.
fn retain<T, const N: usize>(items: &mut Vec<T, N>, mut keep: impl FnMut(&T) -> bool) {
    let mut kept = 0usize;
    for i in 0..items.len() {
        if items.get(i).is_some_and(&mut keep) {
            // (kept ≤ i: the range is never empty; its ends swap, nothing when kept = i)
            if let Some((first, rest)) = items.get_mut(kept..=i).and_then(|s| s.split_first_mut()) {
                if let Some(last) = rest.last_mut() {
                    core::mem::swap(first, last);
                }
            }
            kept = kept.saturating_add(1); // (at most i + 1)
        }
    }
    items.truncate(kept);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::receiver::example::ExampleFlight;
    use crate::signal::SampleBlock;
    use crate::tracking::AcquisitionError;

    type Front = SampleReceiver<2, 1024>;

    fn front() -> Front {
        let mut config = SampleFrontConfig::leo_complex(1.023e6);
        config.acquisition.doppler_max_hz = 1000.0;
        config.acquisition.noncoherent_ms = 2;
        SampleReceiver::new(ExampleFlight::config(false), config).expect("a valid set-up")
    }

    fn detection(prn: u8) -> SearchResult {
        SearchResult {
            prn: Prn::new(prn).expect("a PRN"),
            detected: true,
            metric: 10.0,
            threshold: 1.0,
            doppler_hz: 1200.0,
            code_phase_chips: 100.0,
            first_sample: 0,
        }
    }

    #[test]
    fn channels_start_from_detections_up_to_the_capacity_and_release_by_prn() {
        let mut rx = front();
        rx.start(&detection(3)).expect("room");
        rx.start(&detection(7)).expect("room");
        assert_eq!(
            rx.start(&detection(9)),
            Err(ReceiverError::TooManySatellites)
        );
        assert!(rx.tracks(Prn::new(7).unwrap()));
        assert!(rx.release(Prn::new(3).unwrap()));
        assert!(!rx.release(Prn::new(3).unwrap()));
        assert_eq!(rx.channels().count(), 1);
    }

    /// A warm start: a satellite at +3.3 kHz, outside the ±1 kHz span about zero, is not
    /// found by `search` (no channel) and is found about its predicted +3 kHz by
    /// `search_samples_near`, which starts its channel.
    #[test]
    fn a_warm_search_about_the_predicted_doppler_starts_the_channel() {
        use crate::noise::{SplitMix64, StandardNormal};
        const FS: f64 = 1.023e6;
        let mut rx = front();
        let prn = Prn::new(11).unwrap();
        let n = rx.config.acquisition.samples_needed();
        let (mut rng, mut normal) = (SplitMix64::new(3), StandardNormal::new());
        let (mut i, mut q) = (
            heapless::Vec::<i8, 4200>::new(),
            heapless::Vec::<i8, 4200>::new(),
        );
        for k in 0..n {
            let t = k as f64 / FS;
            let chip = (250.0 + t * crate::signal::CA_CHIP_RATE_HZ) as usize % 1023;
            let c = f64::from(prn.chip(chip));
            let phase = core::f64::consts::TAU * 3300.0 * t;
            let x = 4.0 * c * libm::cos(phase) + 8.0 * f64::from(normal.sample(&mut rng));
            let y = 4.0 * c * libm::sin(phase) + 8.0 * f64::from(normal.sample(&mut rng));
            i.push(libm::round(x) as i8).unwrap();
            q.push(libm::round(y) as i8).unwrap();
        }
        let cold = rx.search(prn, &i, Some(&q), 0).unwrap();
        assert!(!cold.detected && !rx.tracks(prn), "{cold:?}");
        let samples = SearchSamples::decoded(&i, Some(&q)).unwrap();
        let warm = rx.search_samples_near(prn, samples, 0, 3000.0).unwrap();
        assert!(warm.detected && rx.tracks(prn), "{warm:?}");
        assert!((warm.doppler_hz - 3300.0).abs() < 250.0, "{warm:?}");
        assert_eq!(
            rx.search_samples_near(prn, samples, 0, f32::NAN),
            Err(ReceiverError::Acquisition(AcquisitionError::NonFinite))
        );
    }

    #[test]
    fn a_search_on_too_few_samples_is_a_typed_error() {
        let mut rx = front();
        let few = [0i8; 100];
        assert_eq!(
            rx.search(Prn::new(1).unwrap(), &few, Some(&few), 0),
            Err(ReceiverError::Acquisition(
                AcquisitionError::NotEnoughSamples
            ))
        );
        assert_eq!(rx.channels().count(), 0);
    }

    #[test]
    fn noise_alone_gives_epochs_but_no_observations_and_the_channel_is_released() {
        let mut rx = front();
        rx.start(&detection(5)).expect("room");
        // 2.5 s of zero samples (no signal): epochs every ms, never locked
        let zeros = [0i8; 1023];
        let mut total = SampleReport::default();
        for k in 0..2500u64 {
            let block = SampleBlock::complex(k * 1023, [&zeros; 3], [&zeros; 3]).unwrap();
            let r = rx.push_samples(&block).expect("a continuing stream");
            total.epochs += r.epochs;
            total.observations += r.observations;
            total.released += r.released;
        }
        assert!(total.epochs > 1900, "epochs {}", total.epochs);
        assert_eq!(total.observations, 0);
        assert_eq!(total.released, 1);
        assert_eq!(rx.channels().count(), 0);
    }

    /// The observer sees every epoch `push_samples` counts, once, in code-period order, with
    /// the channel's satellite and lock; and observing changes nothing: a twin receiver fed
    /// the same blocks through `push_samples` reports the same and ends in the same state.
    #[test]
    fn the_observer_sees_each_channel_epoch_once_and_changes_nothing() {
        let mut observed = front();
        observed.start(&detection(5)).expect("room");
        observed.start(&detection(9)).expect("room");
        let mut plain = observed.clone();
        let zeros = [0i8; 1023];
        let mut seen: heapless::Vec<(u8, u32, bool), 64> = heapless::Vec::new();
        let mut epochs = 0u32;
        for k in 0..20u64 {
            let block = SampleBlock::complex(k * 1023, [&zeros; 3], [&zeros; 3]).unwrap();
            let a = observed
                .push_samples_observed(&block, &mut |prn, e, locked| {
                    seen.push((prn.number(), e.index, locked)).expect("room");
                })
                .expect("a continuing stream");
            let b = plain.push_samples(&block).expect("a continuing stream");
            assert_eq!(a, b);
            epochs += a.epochs;
        }
        assert!(epochs >= 30, "epochs {epochs}");
        assert_eq!(seen.len(), epochs as usize);
        for prn in [5u8, 9] {
            let indices: heapless::Vec<u32, 64> =
                seen.iter().filter(|s| s.0 == prn).map(|s| s.1).collect();
            assert!(indices.len() >= 15, "PRN {prn}: {indices:?}");
            assert!(indices.windows(2).all(|w| w[1] == w[0] + 1), "{indices:?}");
        }
        // noise alone never locks
        assert!(seen.iter().all(|s| !s.2));
        assert_eq!(
            observed.channels().collect::<heapless::Vec<_, 2>>(),
            plain.channels().collect::<heapless::Vec<_, 2>>()
        );
    }

    /// Deferred checks: the block that ends the channels' lock windows only notes that a
    /// check waits, `run_deferred` runs it, and without that call the next block runs it (an
    /// overrun, counted). Deferring changes nothing else: a twin receiver with the checks
    /// inline sees the same epochs and ends in the same state.
    #[test]
    fn deferred_cross_correlation_checks_wait_for_the_main_loop_or_the_next_block() {
        let mut deferred = front();
        deferred.start(&detection(5)).expect("room");
        deferred.start(&detection(9)).expect("room");
        let mut inline = deferred.clone();
        deferred.set_deferred_checks(true);
        let zeros = [0i8; 1023];
        let (mut ran_in_main_loop, mut waiting_before) = (0, false);
        for k in 0..260u64 {
            let block = SampleBlock::complex(k * 1023, [&zeros; 3], [&zeros; 3]).unwrap();
            let overruns = deferred.check_overruns();
            let a = deferred.push_samples(&block).expect("a continuing stream");
            let b = inline.push_samples(&block).expect("a continuing stream");
            assert_eq!(a.epochs, b.epochs, "block {k}");
            assert!(
                !inline.any_check_pending(),
                "inline checks run in their block"
            );
            if waiting_before {
                assert_eq!(deferred.check_overruns(), overruns + 1, "block {k}");
            }
            waiting_before = deferred.checks_waiting;
            if deferred.checks_waiting {
                assert!(
                    deferred.any_check_pending(),
                    "block {k}: the window is not judged yet"
                );
                if k < 150 {
                    // the main loop's turn: the check runs there
                    deferred.run_deferred();
                    assert!(!deferred.any_check_pending() && !deferred.checks_waiting);
                    ran_in_main_loop += 1;
                    waiting_before = false;
                }
            }
        }
        assert!(
            ran_in_main_loop >= 1,
            "a lock window ended in the first 150 ms"
        );
        assert!(
            deferred.check_overruns() >= 1,
            "and one after them, left to the next block"
        );
        assert_eq!(
            deferred.channels().collect::<heapless::Vec<_, 2>>(),
            inline.channels().collect::<heapless::Vec<_, 2>>()
        );
    }
}
