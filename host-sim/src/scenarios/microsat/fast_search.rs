//! The fast path's acquisition: the receiver decides what to search, the core's acquisition
//! decides what it found, the world only supplies the samples.
//!
//! Every whole second the fast path searches the PRNs of the receiver's own search list
//! ([`SampleLevel::to_search`](super::sample_level::SampleLevel::to_search): almanac, orbit and
//! the receiver's attitude, exactly as the sample-level stretch) that have no channel and whose
//! last failed search is at least [`RETRY_AFTER_S`] old. For each, the world synthesizes the
//! reference antenna's samples a search reads ([`AcquisitionConfig::samples_needed`]: 20 ms
//! plus the 20 ms verification dwell, 2.6 Msps complex, CS8 with the sample-level stretch's
//! gain): that satellite at its true C/N0, Doppler and Doppler rate when the reference antenna
//! receives it (above the mask, not occulted, not blocked), nothing otherwise, plus thermal
//! noise. The core's [`Acquisition`] (±50 kHz, the configuration of the sample-level stretch,
//! its threshold from the search's own background at `P_fa` = 1e-5 per PRN, the verification
//! dwell) searches it; its `detected` alone starts a channel. The block holds no other
//! satellite, so the fast path's false alarms are thermal-noise ones only (the sample-level
//! stretch, with every satellite in its samples, also meets cross-correlations).
//!
//! Searches are counted against the truth as the sample-level stretch counts them: absent
//! (the reference antenna did not receive the PRN), found, false alarms (found but absent),
//! missed (received but not found).

use std::collections::BTreeMap;

use anyhow::{anyhow, Result};
use gnss_attitude::signal::{Prn, SampleFormat};
use gnss_attitude::tracking::{Acquisition, AcquisitionConfig};
use nalgebra::{Matrix3, Vector3};

use super::sample_level::{SampleLevel, RETRY_AFTER_S, SAMPLE_RATE_HZ};
use crate::synth::quantize::Quantizer;
use crate::synth::scene::mix;
use crate::synth::{AttitudeMotion, FrontEnd, Satellite, Scene};

/// The signal of a searched satellite at the reference antenna (the world's truth).
#[derive(Clone, Copy, Debug)]
pub struct SearchedSignal {
    /// C/N0, dB-Hz.
    pub cn0_dbhz: f64,
    /// Doppler, Hz.
    pub doppler_hz: f64,
    /// Doppler rate, Hz/s.
    pub doppler_rate_hz_s: f64,
}

/// What the fast path's searches and channels did.
#[derive(Clone, Debug, Default)]
pub struct FastPathStats {
    /// PRN searches run.
    pub searches: usize,
    /// Searches that found their satellite (each starts a channel).
    pub detections: usize,
    /// Searches of PRNs the reference antenna did not receive.
    pub searches_absent: usize,
    /// Detections of a PRN the reference antenna did not receive.
    pub false_alarms: usize,
    /// Searches of a received PRN that found nothing.
    pub missed: usize,
    /// Channels whose lock detector declared the lock lost.
    pub losses: usize,
    /// For each loss after the reference antenna stopped receiving the satellite: the time
    /// from then to the declaration, s.
    pub loss_delays_s: Vec<f64>,
    /// Wall time of the searches (synthesis and acquisition), s.
    pub acquisition_s: f64,
}

/// The fast path's searches: the core's acquisition and the retry bookkeeping.
pub struct FastSearch {
    acquisition: Box<Acquisition<2048>>,
    config: AcquisitionConfig,
    seed: u64,
    /// The front end that quantizes the search blocks.
    front_end: Quantizer,
    /// When each PRN's last search failed, s.
    failed_at: BTreeMap<u8, f64>,
    /// What the searches and channels did.
    pub stats: FastPathStats,
}

/// Seed salt of the search blocks' noise.
const SEARCH_SEED_SALT: u64 = 0x6661_7374;

impl FastSearch {
    /// The searches of a flight drawn with `seed`, continuing the failed searches of the
    /// sample-level stretch (`failed_at`, s), its blocks quantized by `front_end`.
    pub fn new(seed: u64, failed_at: BTreeMap<u8, f64>, front_end: Quantizer) -> Result<Self> {
        let acquisition = Box::new(Acquisition::<2048>::new().map_err(|e| anyhow!("{e}"))?);
        Ok(Self {
            acquisition,
            config: SampleLevel::front_config().acquisition,
            seed,
            front_end,
            failed_at,
            stats: FastPathStats::default(),
        })
    }

    /// Whether `prn` may be searched at `t` (no failed search in the last [`RETRY_AFTER_S`]).
    pub fn due(&self, prn: u8, t: f64) -> bool {
        self.failed_at
            .get(&prn)
            .is_none_or(|&f| t - f >= RETRY_AFTER_S - 1e-9)
    }

    /// Searches `prn` at `t` (epoch `k`) in a block the world synthesizes with `signal` (the
    /// satellite at the reference antenna, `None` where it does not receive it); returns the
    /// core's decision.
    pub fn search(
        &mut self,
        prn: u8,
        t: f64,
        k: u64,
        signal: Option<SearchedSignal>,
    ) -> Result<bool> {
        let started = std::time::Instant::now();
        let p = Prn::new(prn).ok_or_else(|| anyhow!("PRN {prn}"))?;
        let n = self.config.samples_needed();
        let scene = self.scene(prn, k, signal);
        let analog = scene.synthesize(0, n);
        let planar = self.front_end.quantize(SampleFormat::Cs8, &analog, n)?;
        let (i, q) = (&planar.i[0], &planar.q[0]);
        let detected = self
            .acquisition
            .search(p, i, Some(q), 0, &self.config)
            .map_err(|e| anyhow!("search PRN {prn}: {e}"))?
            .detected;
        let received = signal.is_some();
        let s = &mut self.stats;
        s.searches += 1;
        s.detections += usize::from(detected);
        s.searches_absent += usize::from(!received);
        s.false_alarms += usize::from(detected && !received);
        s.missed += usize::from(!detected && received);
        if detected {
            self.failed_at.remove(&prn);
        } else {
            self.failed_at.insert(prn, t);
        }
        s.acquisition_s += started.elapsed().as_secs_f64();
        Ok(detected)
    }

    /// The one-antenna scene of a search block: the satellite (random code and carrier phase,
    /// data bits) when received, thermal noise always.
    fn scene(&self, prn: u8, k: u64, signal: Option<SearchedSignal>) -> Scene {
        let salt = mix(self.seed ^ SEARCH_SEED_SALT, u64::from(prn), k);
        let satellites = signal
            .map(|s| Satellite {
                prn,
                cn0_dbhz: s.cn0_dbhz,
                doppler_hz: s.doppler_hz,
                doppler_rate_hz_s: s.doppler_rate_hz_s,
                code_phase_chips: (salt % 1_023_000) as f64 * 1e-3,
                carrier_phase_cycles: ((salt >> 20) % 1000) as f64 * 1e-3,
                los_ref: Vector3::z(),
                data_seed: Some(salt ^ 0xda7a),
                track: None,
            })
            .into_iter()
            .collect();
        Scene {
            satellites,
            antennas_b: vec![Vector3::zeros()],
            line_bias_cycles: vec![0.0],
            attitude: AttitudeMotion::Constant(Matrix3::identity()),
            front_end: FrontEnd {
                sample_rate_hz: SAMPLE_RATE_HZ,
                intermediate_frequency_hz: 0.0,
                complex: true,
            },
            noise_seed: Some(salt),
        }
    }
}
