//! Antenna arrays shared by the synthesized scenes (the `signal` scenario and the `synth`
//! recordings).

use nalgebra::Vector3;

/// Paper 003's array: equilateral triangle of side `l`, origin at the middle of AB, X to B,
/// Y to C (body frame, m).
pub fn triangle(l: f64) -> Vec<Vector3<f64>> {
    vec![
        Vector3::new(-l / 2.0, 0.0, 0.0),
        Vector3::new(l / 2.0, 0.0, 0.0),
        Vector3::new(0.0, l * 3f64.sqrt() / 2.0, 0.0),
    ]
}
