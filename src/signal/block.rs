//! A block of decoded samples from all antennas, taken at the same instants (one clock).

use crate::signal::SignalError;

/// Decoded samples of `A` antennas over the same sample instants: antenna `a`'s in-phase
/// samples `i[a]` and, for complex baseband, quadrature samples `q[a]`; all slices have the
/// same length. `first_sample` is the receiver's running sample index of element 0 (the time
/// scale every output is stamped in).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SampleBlock<'a, const A: usize> {
    first_sample: u64,
    i: [&'a [i8]; A],
    q: Option<[&'a [i8]; A]>,
    len: usize,
}

impl<'a, const A: usize> SampleBlock<'a, A> {
    /// A block of real (IF) samples.
    ///
    /// # Errors
    /// [`SignalError::BlockLengthMismatch`] when the antennas' slices differ in length,
    /// [`SignalError::InvalidConfig`] for `A = 0`.
    pub fn real(first_sample: u64, i: [&'a [i8]; A]) -> Result<Self, SignalError> {
        let len = common_len(&i)?;
        Ok(Self {
            first_sample,
            i,
            q: None,
            len,
        })
    }

    /// A block of complex baseband samples.
    ///
    /// # Errors
    /// As [`SampleBlock::real`], also when `q` slices differ in length from the `i` slices.
    pub fn complex(
        first_sample: u64,
        i: [&'a [i8]; A],
        q: [&'a [i8]; A],
    ) -> Result<Self, SignalError> {
        let len = common_len(&i)?;
        if common_len(&q)? != len {
            return Err(SignalError::BlockLengthMismatch);
        }
        Ok(Self {
            first_sample,
            i,
            q: Some(q),
            len,
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

    /// Whether the samples are complex (I/Q).
    pub fn is_complex(&self) -> bool {
        self.q.is_some()
    }

    /// In-phase samples of antenna `a`.
    pub fn i(&self, a: usize) -> Option<&'a [i8]> {
        self.i.get(a).copied()
    }

    /// Quadrature samples of antenna `a` (`None` for real samples).
    pub fn q(&self, a: usize) -> Option<&'a [i8]> {
        self.q.and_then(|q| q.get(a).copied())
    }

    /// The block's first `n` samples, stamped as this one (`None` for `n > len`).
    pub fn head(&self, n: usize) -> Option<Self> {
        if n > self.len {
            return None;
        }
        let cut = |s: &'a [i8]| s.get(..n).unwrap_or_default();
        Some(Self {
            first_sample: self.first_sample,
            i: self.i.map(cut),
            q: self.q.map(|q| q.map(cut)),
            len: n,
        })
    }

    /// The sub-block `[start, start + n)` of antenna `a`: `(i, q)`.
    pub(crate) fn span(
        &self,
        a: usize,
        start: usize,
        n: usize,
    ) -> Option<(&'a [i8], Option<&'a [i8]>)> {
        let end = start.checked_add(n)?;
        let i = self.i.get(a)?.get(start..end)?;
        let q = match self.q {
            Some(q) => Some(q.get(a)?.get(start..end)?),
            None => None,
        };
        Some((i, q))
    }
}

fn common_len(slices: &[&[i8]]) -> Result<usize, SignalError> {
    let first = slices.first().ok_or(SignalError::InvalidConfig)?.len();
    if slices.iter().all(|s| s.len() == first) {
        Ok(first)
    } else {
        Err(SignalError::BlockLengthMismatch)
    }
}
