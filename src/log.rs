//! Logging that costs nothing without the `defmt` feature.
//!
//! `debug!`, `info!` and `warn!` forward to defmt when the feature is on. Without it they expand
//! to a borrow of each argument (so that a variable used only for logging does not warn) and
//! compile to nothing.

#[cfg(feature = "defmt")]
#[allow(unused_macros)]
macro_rules! debug {
    ($($arg:tt)+) => { ::defmt::debug!($($arg)+) };
}

#[cfg(not(feature = "defmt"))]
#[allow(unused_macros)]
macro_rules! debug {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}

#[cfg(feature = "defmt")]
#[allow(unused_macros)]
macro_rules! info {
    ($($arg:tt)+) => { ::defmt::info!($($arg)+) };
}

#[cfg(not(feature = "defmt"))]
#[allow(unused_macros)]
macro_rules! info {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}

#[cfg(feature = "defmt")]
#[allow(unused_macros)]
macro_rules! warn {
    ($($arg:tt)+) => { ::defmt::warn!($($arg)+) };
}

#[cfg(not(feature = "defmt"))]
#[allow(unused_macros)]
macro_rules! warn {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}
