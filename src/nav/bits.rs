//! Data bits from 1 ms prompts: bit synchronization by a histogram of sign changes over the 20
//! epoch phases of a 20 ms LNAV bit, then bits from the prompts summed over each bit.
//!
//! The idea is the receiver's bit-edge monitor (`receiver::satellite`): the sign of the
//! prompt's in-phase component changes only at bit edges, so over many bits the edge phase
//! collects the changes and noise spreads its changes over all phases. The decision is a
//! confidence test on the counts: the best phase must hold at least
//! [`BitSyncConfig::min_edge_transitions`] changes and beat the runner-up by a margin of
//! [`BitSyncConfig::z_score`] standard deviations of the difference of two Poisson counts
//! (`√(b + s)`), so at low C/N0, where noise flips many signs, the test waits for more bits
//! instead of deciding on a noise peak.
//!
//! Epochs are the tracking channel's code-period count (one per 1 ms code period of the
//! satellite's signal), so a bit edge is always at the same `epoch % 20`.

/// Epochs (1 ms code periods) per LNAV data bit.
pub const EPOCHS_PER_BIT: u64 = 20;

/// Histogram count at which every bin is halved (keeps the counts bounded and lets the
/// histogram follow a re-acquisition).
const HISTOGRAM_CAP: u16 = 4096;

/// Configuration of [`BitSynchronizer`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitSyncConfig {
    /// Sign changes the best phase must hold before a decision (random data changes sign at
    /// half of the bit edges: 20 changes take about 0.8 s).
    pub min_edge_transitions: u16,
    /// Margin of the best phase over the runner-up, in standard deviations `√(b + s)`.
    pub z_score: f32,
}

impl Default for BitSyncConfig {
    fn default() -> Self {
        Self {
            min_edge_transitions: 20,
            z_score: 5.0,
        }
    }
}

/// Error returned by [`BitSynchronizer::push`] and [`BitDecoder::push`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BitError {
    /// The prompt was NaN or infinite.
    #[error("non-finite prompt")]
    NonFinite,
    /// The epoch did not follow the previous one (equal or earlier).
    #[error("epoch out of order")]
    OutOfOrder,
    /// Epochs were missing inside a data bit: the partial bit is dropped and the bit stream
    /// is broken (a subframe synchronizer must start over).
    #[error("epochs missing inside a bit")]
    Gap,
}

impl crate::error::Error for BitError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::NonFinite => crate::error::ErrorKind::NonFinite,
            Self::OutOfOrder | Self::Gap => crate::error::ErrorKind::InvalidInput,
        }
    }
}

/// Bit synchronization: learns the epoch phase (`epoch % 20`) at which data bits start.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitSynchronizer {
    config: BitSyncConfig,
    histogram: [u16; 20],
    last: Option<(u64, bool)>,
    edge: Option<u8>,
}

impl BitSynchronizer {
    /// An unsynchronized synchronizer.
    pub fn new(config: BitSyncConfig) -> Self {
        Self {
            config,
            histogram: [0; 20],
            last: None,
            edge: None,
        }
    }

    /// The phase (`epoch % 20`) of the first epoch of every bit, once decided.
    pub fn edge(&self) -> Option<u8> {
        self.edge
    }

    /// Takes the prompt I (any unit) of `epoch`; returns the edge phase once decided.
    ///
    /// # Errors
    /// [`BitError::NonFinite`], [`BitError::OutOfOrder`]; the synchronizer is unchanged.
    pub fn push(&mut self, epoch: u64, prompt_i: f32) -> Result<Option<u8>, BitError> {
        if !prompt_i.is_finite() {
            return Err(BitError::NonFinite);
        }
        let positive = prompt_i >= 0.0;
        if let Some((last_epoch, last_positive)) = self.last {
            if epoch <= last_epoch {
                return Err(BitError::OutOfOrder);
            }
            // only a change between consecutive epochs says where it happened
            if last_epoch.checked_add(1) == Some(epoch)
                && positive != last_positive
                && self.edge.is_none()
            {
                self.count_change(epoch);
                self.edge = self.decide();
            }
        }
        self.last = Some((epoch, positive));
        Ok(self.edge)
    }

    fn count_change(&mut self, epoch: u64) {
        let phase = (epoch % EPOCHS_PER_BIT) as usize;
        if let Some(h) = self.histogram.get_mut(phase) {
            *h = h.saturating_add(1);
            if *h >= HISTOGRAM_CAP {
                for h in self.histogram.iter_mut() {
                    *h /= 2;
                }
            }
        }
    }

    /// The confidence test: best phase `b`, runner-up `s`; decided when
    /// `b ≥ min_edge_transitions` and `b − s ≥ z √(b + s)`.
    fn decide(&self) -> Option<u8> {
        let (mut best, mut at, mut second) = (0u16, 0usize, 0u16);
        for (k, &h) in self.histogram.iter().enumerate() {
            if h > best {
                second = best;
                best = h;
                at = k;
            } else if h > second {
                second = h;
            }
        }
        let (b, s) = (f32::from(best), f32::from(second));
        let confident = best >= self.config.min_edge_transitions
            && b - s >= self.config.z_score * crate::sqrtf(b + s);
        confident.then_some(at as u8)
    }

    /// Forgets everything (after a loss of lock).
    pub fn reset(&mut self) {
        *self = Self::new(self.config);
    }
}

/// One data bit: the sign of the prompts summed over its 20 epochs.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DataBit {
    /// `true` when the sum was positive (the polarity of the whole stream is unknown until
    /// the preamble is found).
    pub value: bool,
    /// Epoch (code period) at which the bit started.
    pub start_epoch: u64,
    /// `|Σ I|` over the bit, the prompt's unit (a reliability measure).
    pub strength: f32,
}

/// Bit synchronization followed by bit integration: 1 ms prompts in, data bits out.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitDecoder {
    sync: BitSynchronizer,
    sum: f32,
    count: u64,
    bit_start: Option<u64>,
    last_epoch: Option<u64>,
}

impl BitDecoder {
    /// A decoder that has not synchronized yet.
    pub fn new(config: BitSyncConfig) -> Self {
        Self {
            sync: BitSynchronizer::new(config),
            sum: 0.0,
            count: 0,
            bit_start: None,
            last_epoch: None,
        }
    }

    /// The bit edge phase, once known.
    pub fn edge(&self) -> Option<u8> {
        self.sync.edge()
    }

    /// Takes the prompt I of `epoch`; returns a bit when `epoch` was the last epoch of one.
    ///
    /// # Errors
    /// [`BitError::NonFinite`] and [`BitError::OutOfOrder`] (decoder unchanged);
    /// [`BitError::Gap`] when epochs were missing inside the current bit (the partial bit is
    /// dropped, the epoch counted towards the next one when it starts one).
    pub fn push(&mut self, epoch: u64, prompt_i: f32) -> Result<Option<DataBit>, BitError> {
        let Some(edge) = self.sync.push(epoch, prompt_i)? else {
            self.last_epoch = Some(epoch);
            return Ok(None);
        };
        let gap = self
            .last_epoch
            .is_some_and(|last| last.checked_add(1) != Some(epoch));
        self.last_epoch = Some(epoch);
        let starts_bit = epoch % EPOCHS_PER_BIT == u64::from(edge);
        if gap && self.bit_start.is_some() && !starts_bit {
            self.bit_start = None;
            return Err(BitError::Gap);
        }
        if starts_bit {
            let broken = gap && self.bit_start.is_some();
            self.bit_start = Some(epoch);
            self.sum = 0.0;
            self.count = 0;
            if broken {
                self.accumulate(prompt_i);
                return Err(BitError::Gap);
            }
        }
        if self.bit_start.is_none() {
            return Ok(None);
        }
        Ok(self.accumulate(prompt_i))
    }

    fn accumulate(&mut self, prompt_i: f32) -> Option<DataBit> {
        self.sum += prompt_i;
        // (restarted at every bit: at most EPOCHS_PER_BIT)
        self.count = self.count.saturating_add(1);
        if self.count < EPOCHS_PER_BIT {
            return None;
        }
        let start_epoch = self.bit_start.take()?;
        Some(DataBit {
            value: self.sum > 0.0,
            start_epoch,
            strength: libm::fabsf(self.sum),
        })
    }

    /// Forgets the synchronization and the partial bit.
    pub fn reset(&mut self) {
        let config = self.sync.config;
        *self = Self::new(config);
    }
}

#[cfg(test)]
mod tests {
    use heapless::Vec;

    use super::*;

    /// Room for one bit per 20 ms of the longest run (20 s).
    const BITS: usize = 1024;

    /// xorshift for reproducible bits and noise.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0
        }
        /// Approximately normal (sum of 12 uniforms − 6).
        fn normal(&mut self) -> f32 {
            (0..12)
                .map(|_| (self.next() >> 40) as f32 / (1u64 << 24) as f32)
                .sum::<f32>()
                - 6.0
        }
    }

    type Run = (Option<u8>, Vec<DataBit, BITS>, Vec<(u64, bool), BITS>);

    fn run(amplitude: f32, edge: u64, epochs: u64, seed: u64) -> Run {
        let mut rng = Rng(seed);
        let mut dec = BitDecoder::new(BitSyncConfig::default());
        let mut truth = Vec::new();
        let mut bits = Vec::new();
        let mut value = true;
        for k in 0..epochs {
            if k % 20 == edge {
                value = rng.next() & 1 == 1;
                truth.push((1000 + k, value)).expect("room for every bit");
            }
            let s = if value { amplitude } else { -amplitude };
            if let Some(b) = dec.push(1000 + k, s + rng.normal()).unwrap() {
                bits.push(b).expect("room for every bit");
            }
        }
        (dec.edge(), bits, truth)
    }

    #[test]
    fn strong_signal_synchronizes_within_a_second_and_bits_match() {
        // 45 dB-Hz: 1 ms amplitude √(2 C/N0 T) ≈ 8 noise σ
        let (edge, bits, truth) = run(8.0, 7, 6000, 1);
        assert_eq!(edge, Some(((1000 + 7) % 20) as u8));
        assert!(bits.len() > 240, "{}", bits.len());
        let first = bits[0];
        assert!(
            first.start_epoch < 1000 + 1200,
            "sync at {}",
            first.start_epoch
        );
        for b in &bits {
            let t = truth.iter().find(|t| t.0 == b.start_epoch).unwrap();
            assert_eq!(b.value, t.1, "bit at {}", b.start_epoch);
        }
    }

    #[test]
    fn weak_signal_waits_and_still_finds_the_edge() {
        // 30 dB-Hz: amplitude 1.4 σ per ms, 8 % sign errors
        let (edge, bits, _) = run(1.41, 13, 20_000, 2);
        assert_eq!(edge, Some(((1000 + 13) % 20) as u8));
        assert!(!bits.is_empty());
    }

    #[test]
    fn noise_alone_never_synchronizes() {
        for seed in 3..8 {
            let (edge, _, _) = run(0.0, 0, 20_000, seed);
            assert_eq!(edge, None, "seed {seed}");
        }
    }

    #[test]
    fn a_gap_inside_a_bit_breaks_the_stream_and_bad_input_is_refused() {
        let mut dec = BitDecoder::new(BitSyncConfig::default());
        let mut k = 0u64;
        let mut value = 1.0f32;
        while dec.edge().is_none() {
            if k % 20 == 0 {
                value = -value;
            }
            dec.push(k, value).unwrap();
            k += 1;
        }
        while k % 20 != 5 {
            dec.push(k, value).unwrap();
            k += 1;
        }
        assert_eq!(dec.push(k + 3, value), Err(BitError::Gap));
        assert_eq!(dec.push(k + 3, value), Err(BitError::OutOfOrder));
        assert_eq!(dec.push(k + 4, f32::NAN), Err(BitError::NonFinite));
    }
}
