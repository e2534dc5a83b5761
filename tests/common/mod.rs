//! Signals shared by the integration tests: references with consistent derivatives.
#![allow(dead_code)]

pub mod fmu;

use shaketable::campaign::synth::ReferenceSignal;
use shaketable::{Inputs, Reference};
use std::f64::consts::PI;

pub const FS: f64 = 512.0;

/// A sine reference with consistent derivatives, `seconds` long at [`FS`].
pub fn sine(amplitude_m: f64, frequency_hz: f64, seconds: f64) -> Vec<Inputs> {
    let w = 2.0 * PI * frequency_hz;
    (0..(seconds * FS) as usize)
        .map(|k| {
            let t = k as f64 / FS;
            Inputs {
                reference: Reference {
                    displacement_m: amplitude_m * (w * t).sin(),
                    velocity_m_s: amplitude_m * w * (w * t).cos(),
                    acceleration_m_s2: -amplitude_m * w * w * (w * t).sin(),
                },
                external_force_n: 0.0,
            }
        })
        .collect()
}

/// The model inputs of a synthesised reference.
pub fn inputs_of(r: &ReferenceSignal) -> Vec<Inputs> {
    r.inputs()
}
