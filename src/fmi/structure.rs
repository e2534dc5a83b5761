//! Which continuous states each output reads (ModelStructure `dependencies` under Model
//! Exchange, where the states are knowns), found from the model itself: each state is
//! moved in turn at a generic operating point and the outputs that change are recorded.
//! The union over the structural choices and with every effect on makes the list hold for
//! any parameter set (a state an output never reads in one configuration may be listed;
//! one it reads is never missing).

use crate::effects::CATALOGUE;
use crate::model::{Inputs, Model, Outputs, Reference, SensorNoise, NX};
use crate::params::{ActuatorModel, Params, ServovalveModel};

/// Relative size of the probe on each state: far above rounding, small enough to stay on
/// the same branch of every switch at the operating point.
const PROBE_RELATIVE: f64 = 1e-6;

/// Parameter sets covering the structural choices, every effect on and every controller
/// gain nonzero (so no dependency hides behind a zero gain).
fn probe_parameters() -> Vec<Params> {
    let mut sets = Vec::new();
    for actuator in [ActuatorModel::Ideal, ActuatorModel::Nonlinear] {
        for valve in [ServovalveModel::FirstOrder, ServovalveModel::SecondOrder] {
            let mut p = Params::trees_lab();
            p.actuator.model = actuator;
            p.servovalve.model = valve;
            for e in &CATALOGUE {
                e.set_enabled(&mut p, true);
            }
            p.valve_deadband.deadband = 1e-4;
            p.table.stiffness_n_m = 1e5;
            p.controller.kv = 1e-2;
            p.controller.ka = 1e-3;
            p.controller.fa = 1e-3;
            // every specimen mode present
            p.specimen.mode2.mass_kg = 4000.0;
            p.specimen.mode3.mass_kg = 2000.0;
            // with free play the LVDT and the flow read the rod instead of the table: the
            // union takes both
            sets.push(Params {
                free_play: Default::default(),
                ..p
            });
            sets.push(p);
        }
    }
    sets
}

/// A generic operating point: every state away from zero and from every switch, the
/// table slow enough (3 mm/s relative) for the Stribeck curve to depend on its speed.
fn operating_point(m: &Model) -> [f64; NX] {
    let mut s = m.rest_state();
    // the free-play rod 0.3 mm ahead of the table and closing: past the default 0.1-mm
    // half gap, its contact pushing
    let generic = [
        0.02, 0.3, 2e5, -1e5, 0.011, 0.004, 0.4, 0.012, 0.14, 1e-4, 1e-3, 0.013, 0.12, 0.014, 0.11,
        0.0113, 0.0045,
    ];
    for (x, g) in s.iter_mut().zip(generic) {
        *x += g;
    }
    s
}

/// Indices of the states `read` depends on.
pub fn output_state_dependencies(read: fn(&Outputs) -> f64) -> Vec<usize> {
    let inp = Inputs {
        reference: Reference {
            displacement_m: 0.01,
            velocity_m_s: 0.1,
            acceleration_m_s2: 1.0,
        },
        external_force_n: 1e3,
    };
    let noise = SensorNoise::default();
    let mut found = [false; NX];
    for p in probe_parameters() {
        let m = Model::new(&p);
        let s0 = operating_point(&m);
        let y0 = read(&m.outputs(&s0, &inp, &noise, 0.0));
        for (k, hit) in found.iter_mut().enumerate() {
            let mut s = s0;
            s[k] += PROBE_RELATIVE * s0[k].abs().max(1e-3);
            *hit |= read(&m.outputs(&s, &inp, &noise, 0.0)) != y0;
        }
    }
    (0..NX).filter(|&k| found[k]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::ix;

    #[test]
    fn outputs_read_the_states_the_physics_says() {
        // the LVDT reads the table, or with free play the actuator rod
        let d = output_state_dependencies(|o| o.displacement_m);
        assert_eq!(d, vec![ix::X, ix::XF, ix::XR]);
        let f = output_state_dependencies(|o| o.actuator_force_n);
        assert_eq!(f, vec![ix::PA, ix::PB]);
        let a = output_state_dependencies(|o| o.acceleration_m_s2);
        for k in [
            ix::PA,
            ix::PB,
            ix::X,
            ix::V,
            ix::Z,
            ix::XS,
            ix::VS,
            ix::XF,
            ix::VF,
            ix::XS2,
            ix::VS2,
            ix::XS3,
            ix::VS3,
            ix::XR,
            ix::VR,
        ] {
            assert!(a.contains(&k), "acceleration must read state {k}: {a:?}");
        }
        assert!(!a.contains(&ix::XV));
        assert_eq!(
            output_state_dependencies(|o| o.spool_position),
            vec![ix::XV]
        );
    }
}
