//! Strategies shared by the fuzz tests.

use proptest::prelude::*;

/// A float that is sometimes ordinary and often poisoned: NaN, ±∞, the extremes, tiny and zero.
pub fn poisoned_float() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -2.0f32..2.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(f32::MAX),
        1 => Just(f32::MIN_POSITIVE),
        1 => Just(1e30f32),
        1 => Just(-1e-30f32),
        1 => Just(0.0f32),
    ]
}
