//! The reports' lines, written through semihosting without `core::fmt`.
//!
//! `core::fmt` (its `Formatter`, padding, the `Debug` and `Display` impls a report names, the
//! argument tables) costs this firmware about 15 KiB of flash, more than any stage of the
//! receiver but two; a flight build prints through `defmt` and carries none of it either.
//! [`say!`](crate::say) writes its arguments one after the other, each through [`Say`]:
//! strings as they are, integers in decimal, [`Fixed`](super::fixed::Fixed) decimals, and the
//! core's errors as their [`ErrorKind`] (a `Debug` print of the error chain would link
//! `core::fmt` again).

use core::cell::Cell;

use cortex_m::interrupt::{self, Mutex};
use cortex_m_semihosting::hio::{self, HostStream};
use gnss_attitude::error::{Error, ErrorKind};
use gnss_attitude::receiver::AttitudeSource;
use gnss_attitude::signal::bitwise::CarrierLevels;

/// Bytes gathered before one semihosting write (a longer line takes several).
const BUFFER: usize = 96;

/// The host's standard output, opened by the first line.
static STDOUT: Mutex<Cell<Option<HostStream>>> = Mutex::new(Cell::new(None));

/// One line being written: its bytes gathered, written when the buffer fills and at the end.
pub struct Line {
    buf: [u8; BUFFER],
    len: usize,
}

impl Line {
    /// An empty line.
    pub fn new() -> Self {
        Self { buf: [0; BUFFER], len: 0 }
    }

    /// Appends `bytes`, writing out each full buffer.
    pub fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.len == BUFFER {
                self.flush();
            }
            self.buf[self.len] = b;
            self.len += 1;
        }
    }

    /// Ends the line (a newline) and writes it out.
    pub fn end(mut self) {
        self.bytes(b"\n");
        self.flush();
    }

    /// Writes the gathered bytes to the host (dropped when the host has no output: there is
    /// no one to tell).
    #[inline(never)]
    fn flush(&mut self) {
        let bytes = &self.buf[..self.len];
        interrupt::free(|cs| {
            let stdout = STDOUT.borrow(cs);
            if let Some(mut out) = stdout.get().or_else(|| hio::hstdout().ok()) {
                let _ = out.write_all(bytes);
                stdout.set(Some(out));
            }
        });
        self.len = 0;
    }
}

/// A value a report line can show.
pub trait Say {
    /// Appends the value's text to `line`.
    fn say(&self, line: &mut Line);
}

impl Say for &str {
    fn say(&self, line: &mut Line) {
        line.bytes(self.as_bytes());
    }
}

impl Say for bool {
    fn say(&self, line: &mut Line) {
        line.bytes(if *self { b"true" } else { b"false" });
    }
}

impl Say for u64 {
    fn say(&self, line: &mut Line) {
        decimal(line, *self, 1);
    }
}

/// Appends `v` in decimal with at least `width` digits (leading zeros; at most 20).
#[inline(never)]
#[optimize(size)]
pub fn decimal(line: &mut Line, v: u64, width: usize) {
    let mut digits = [b'0'; 20];
    let mut v = v;
    let mut first = digits.len();
    loop {
        first -= 1;
        digits[first] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    line.bytes(&digits[first.min(digits.len().saturating_sub(width))..]);
}

/// Unsigned integers narrower than `u64`, shown as `u64`.
macro_rules! say_as_u64 {
    ($($t:ty),*) => {$(
        impl Say for $t {
            fn say(&self, line: &mut Line) {
                u64::from(*self).say(line);
            }
        }
    )*};
}
say_as_u64!(u8, u16, u32);

impl Say for usize {
    fn say(&self, line: &mut Line) {
        (*self as u64).say(line);
    }
}

impl<T: Say> Say for Option<T> {
    /// As `Debug` shows it: `Some(value)` or `None`.
    fn say(&self, line: &mut Line) {
        match self {
            Some(v) => {
                line.bytes(b"Some(");
                v.say(line);
                line.bytes(b")");
            }
            None => line.bytes(b"None"),
        }
    }
}

impl Say for AttitudeSource {
    /// The variant's name, as `Debug` shows it.
    fn say(&self, line: &mut Line) {
        line.bytes(match self {
            AttitudeSource::None => b"None",
            AttitudeSource::Snapshot => b"Snapshot",
            AttitudeSource::Fine => b"Fine",
            AttitudeSource::GyroCoast => b"GyroCoast",
        });
    }
}

impl Say for CarrierLevels {
    /// The variant's name, as `Debug` shows it.
    fn say(&self, line: &mut Line) {
        line.bytes(match self {
            CarrierLevels::Two => b"Two",
            CarrierLevels::Three => b"Three",
        });
    }
}

/// A hexadecimal word, `0x` and eight digits.
pub struct Hex(pub u32);

impl Say for Hex {
    fn say(&self, line: &mut Line) {
        let mut text = *b"0x00000000";
        for (k, c) in text[2..].iter_mut().enumerate() {
            let nibble = (self.0 >> (28 - 4 * k)) & 0xF;
            *c = b"0123456789abcdef"[nibble as usize];
        }
        line.bytes(&text);
    }
}

/// One of the core's errors, shown as its [`ErrorKind`] (`refused (invalid input)`).
pub struct Refusal<'a, E: Error>(pub &'a E);

impl<E: Error> Say for Refusal<'_, E> {
    fn say(&self, line: &mut Line) {
        line.bytes(b"refused (");
        line.bytes(kind_name(self.0.kind()).as_bytes());
        line.bytes(b")");
    }
}

/// [`ErrorKind::as_str`], out of line (one copy for every error type).
#[inline(never)]
fn kind_name(kind: ErrorKind) -> &'static str {
    kind.as_str()
}

/// Writes one line of the values given, each through [`Say`]:
/// `say!("realtime ", name, ": ", n, " PRNs")`.
macro_rules! say {
    ($($value:expr),+ $(,)?) => {{
        let mut line = $crate::say::Line::new();
        $( $crate::say::Say::say(&$value, &mut line); )+
        line.end();
    }};
}
