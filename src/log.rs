//! Logging that costs nothing without the `defmt` or `log` feature.
//!
//! `debug!`, `info!` and `warn!` forward to defmt when that feature is on, else to the `log`
//! crate when `log` is on (defmt takes precedence when both are: one crate never logs
//! twice). Without either they expand to a borrow of each argument (so that a variable used
//! only for logging does not warn) and compile to nothing. The format strings are written
//! for defmt; the `log` backend writes the template followed by the arguments' `Debug`.

#[cfg(feature = "defmt")]
#[allow(unused_macros)]
macro_rules! debug {
    ($($arg:tt)+) => { ::defmt::debug!($($arg)+) };
}

#[cfg(all(feature = "log", not(feature = "defmt")))]
#[allow(unused_macros)]
macro_rules! debug {
    // the defmt template (with its `{=type}` hints) followed by the arguments' Debug
    ($fmt:literal $(, $arg:expr)* $(,)?) => { ::log::debug!("{} {:?}", $fmt, ($(&$arg,)*)) };
}

#[cfg(not(any(feature = "defmt", feature = "log")))]
#[allow(unused_macros)]
macro_rules! debug {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}

#[cfg(feature = "defmt")]
#[allow(unused_macros)]
macro_rules! info {
    ($($arg:tt)+) => { ::defmt::info!($($arg)+) };
}

#[cfg(all(feature = "log", not(feature = "defmt")))]
#[allow(unused_macros)]
macro_rules! info {
    // the defmt template (with its `{=type}` hints) followed by the arguments' Debug
    ($fmt:literal $(, $arg:expr)* $(,)?) => { ::log::info!("{} {:?}", $fmt, ($(&$arg,)*)) };
}

#[cfg(not(any(feature = "defmt", feature = "log")))]
#[allow(unused_macros)]
macro_rules! info {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}

#[cfg(feature = "defmt")]
#[allow(unused_macros)]
macro_rules! warn {
    ($($arg:tt)+) => { ::defmt::warn!($($arg)+) };
}

#[cfg(all(feature = "log", not(feature = "defmt")))]
#[allow(unused_macros)]
macro_rules! warn {
    // the defmt template (with its `{=type}` hints) followed by the arguments' Debug
    ($fmt:literal $(, $arg:expr)* $(,)?) => { ::log::warn!("{} {:?}", $fmt, ($(&$arg,)*)) };
}

#[cfg(not(any(feature = "defmt", feature = "log")))]
#[allow(unused_macros)]
macro_rules! warn {
    ($fmt:literal $(, $arg:expr)* $(,)?) => {{ $( let _ = &$arg; )* }};
}
