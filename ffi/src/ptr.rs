//! Checked access to what C passes: null and alignment checks before every dereference.

use crate::status::GaStatus;

/// Reads a `T` from `p`.
///
/// # Safety
/// `p` is null or points to a readable, initialized `T` (any bit pattern of `T`'s fields is
/// a valid `T`: the mirrors read from C have only integer and float fields).
pub(crate) unsafe fn read<T: Copy>(p: *const T) -> Result<T, GaStatus> {
    if p.is_null() {
        return Err(GaStatus::NullPointer);
    }
    if !p.is_aligned() {
        return Err(GaStatus::Misaligned);
    }
    // SAFETY: non-null and aligned (checked); readable and initialized by the caller's
    // contract.
    Ok(unsafe { p.read() })
}

/// Writes `value` to `p`.
///
/// # Safety
/// `p` is null or points to memory writable as a `T` that no Rust reference aliases.
pub(crate) unsafe fn write<T>(p: *mut T, value: T) -> Result<(), GaStatus> {
    if p.is_null() {
        return Err(GaStatus::NullPointer);
    }
    if !p.is_aligned() {
        return Err(GaStatus::Misaligned);
    }
    // SAFETY: non-null and aligned (checked); writable by the caller's contract; `T` of the
    // mirrors has no drop glue, so not reading the old value leaks nothing.
    unsafe { p.write(value) };
    Ok(())
}

/// A slice of `len` `T` at `p` (`len = 0` gives an empty slice whatever `p` is).
///
/// # Safety
/// For `len > 0`, `p` points to `len` readable, initialized `T` that nothing writes while the
/// slice lives.
pub(crate) unsafe fn slice<'a, T>(p: *const T, len: usize) -> Result<&'a [T], GaStatus> {
    if len == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(GaStatus::NullPointer);
    }
    if !p.is_aligned() {
        return Err(GaStatus::Misaligned);
    }
    if len
        .checked_mul(core::mem::size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return Err(GaStatus::InvalidInput);
    }
    // SAFETY: non-null, aligned, `len` elements readable and not written while borrowed (the
    // caller's contract), total size within `isize::MAX` (checked).
    Ok(unsafe { core::slice::from_raw_parts(p, len) })
}

/// A mutable byte slice of `len` bytes at `p`.
///
/// # Safety
/// For `len > 0`, `p` points to `len` writable bytes that nothing else accesses while the
/// slice lives.
pub(crate) unsafe fn bytes_mut<'a>(p: *mut u8, len: usize) -> Result<&'a mut [u8], GaStatus> {
    if len == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(GaStatus::NullPointer);
    }
    if len > isize::MAX as usize {
        return Err(GaStatus::InvalidInput);
    }
    // SAFETY: non-null, `u8` needs no alignment, `len` bytes writable and exclusively ours by
    // the caller's contract, size within `isize::MAX` (checked).
    Ok(unsafe { core::slice::from_raw_parts_mut(p, len) })
}

/// Reads `N` consecutive `T` at `p` (a C array parameter `const T p[N]`).
///
/// # Safety
/// `p` is null or points to `N` readable, initialized `T`.
pub(crate) unsafe fn array<T: Copy, const N: usize>(p: *const T) -> Result<[T; N], GaStatus> {
    // SAFETY: the caller's contract.
    let s = unsafe { slice(p, N) }?;
    <[T; N]>::try_from(s).map_err(|_| GaStatus::InvalidInput)
}

/// Writes `N` consecutive `T` to `p` (a C array parameter `T p[N]`).
///
/// # Safety
/// `p` is null or points to `N` writable `T` that no Rust reference aliases.
pub(crate) unsafe fn write_array<T, const N: usize>(
    p: *mut T,
    value: [T; N],
) -> Result<(), GaStatus> {
    // SAFETY: the caller's contract; `[T; N]` has the alignment of `T`.
    unsafe { write(p.cast::<[T; N]>(), value) }
}
