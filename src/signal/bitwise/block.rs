//! A block of bit planes of all antennas over the same sample instants, with the front end's
//! code table: what every satellite's [`BitCorrelator`](super::BitCorrelator) reads.

use super::code::CodeTable;
use super::planes::{AntennaPlanes, PlaneError, PlaneFormat};

/// The planes of `A` antennas over the same `len` sample instants (one clock), starting at
/// receiver sample `first_sample`, and the code table of the front end's sample rate.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitBlock<'a, const A: usize> {
    first_sample: u64,
    len: usize,
    format: PlaneFormat,
    planes: [AntennaPlanes<'a>; A],
    table: &'a CodeTable,
}

impl<'a, const A: usize> BitBlock<'a, A> {
    /// A block from the antennas' planes (antenna 0 is the reference).
    ///
    /// # Errors
    /// [`PlaneError::BlockMismatch`] when the planes differ in sample count or format, or for
    /// `A = 0`.
    pub fn new(
        first_sample: u64,
        table: &'a CodeTable,
        planes: [AntennaPlanes<'a>; A],
    ) -> Result<Self, PlaneError> {
        let first = planes.first().ok_or(PlaneError::BlockMismatch)?;
        let (len, format) = (first.len(), first.format());
        if planes
            .iter()
            .any(|p| p.len() != len || p.format() != format)
        {
            return Err(PlaneError::BlockMismatch);
        }
        Ok(Self {
            first_sample,
            len,
            format,
            planes,
            table,
        })
    }

    /// Sample instants in the block.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the block holds no samples.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Receiver sample index of the block's first sample.
    pub fn first_sample(&self) -> u64 {
        self.first_sample
    }

    /// What the planes hold.
    pub fn format(&self) -> PlaneFormat {
        self.format
    }

    /// The planes of antenna `a`.
    pub fn planes(&self, a: usize) -> Option<&AntennaPlanes<'a>> {
        self.planes.get(a)
    }

    /// The block's first `n` samples, stamped as this one (`None` for `n > len`).
    pub fn head(&self, n: usize) -> Option<Self> {
        if n > self.len {
            return None;
        }
        Some(Self {
            first_sample: self.first_sample,
            len: n,
            format: self.format,
            planes: self.planes.map(|p| p.head(n)),
            table: self.table,
        })
    }

    /// The code table.
    pub fn table(&self) -> &'a CodeTable {
        self.table
    }
}
