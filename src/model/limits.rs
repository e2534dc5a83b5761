//! Operating limits (spec section 8): the envelope a real table never leaves. The model
//! has no end stops or relief valves, so a state beyond it describes nothing real and
//! the run must stop with the time and the limit.

use super::{ix, Outputs, State};
use crate::params::{ActuatorModel, Params};

/// The LVDT displacement may reach this many strokes before the run stops (spec 8).
pub const STROKE_FACTOR: f64 = 1.1;
/// The table speed relative to the reaction mass may reach this many times the
/// velocity limit (spec 8).
pub const VELOCITY_FACTOR: f64 = 2.0;
/// Highest chamber pressure, and highest `|P_L|` of the ideal actuator, in supply
/// pressures (spec 8: a relief valve opens before).
pub const PRESSURE_HIGH_FACTOR: f64 = 1.1;
/// Lowest chamber pressure of the nonlinear actuator, in supply pressures (spec 8: oil
/// cavitates near zero absolute pressure; -0.1 P_s leaves room for the model's
/// smoothing).
pub const PRESSURE_LOW_FACTOR: f64 = -0.1;

/// Which limit a state broke, with the values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Exceeded {
    /// `|x - x_f|` beyond [`STROKE_FACTOR`] strokes.
    Stroke { displacement_m: f64, limit_m: f64 },
    /// `|v - v_f|` beyond [`VELOCITY_FACTOR`] velocity limits.
    Velocity { velocity_m_s: f64, limit_m_s: f64 },
    /// A pressure outside `[low, high]`; `name` says which.
    Pressure {
        name: &'static str,
        pressure_pa: f64,
        low_pa: f64,
        high_pa: f64,
    },
    /// A state that is NaN or infinite.
    NonFinite,
}

impl std::fmt::Display for Exceeded {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Exceeded::Stroke {
                displacement_m,
                limit_m,
            } => write!(
                f,
                "stroke limit: LVDT displacement {displacement_m:.4} m beyond \
                 {STROKE_FACTOR} x limits.stroke_m = {limit_m:.4} m"
            ),
            Exceeded::Velocity {
                velocity_m_s,
                limit_m_s,
            } => write!(
                f,
                "velocity limit: table velocity {velocity_m_s:.4} m/s beyond \
                 {VELOCITY_FACTOR} x limits.velocity_m_s = {limit_m_s:.4} m/s"
            ),
            Exceeded::Pressure {
                name,
                pressure_pa,
                low_pa,
                high_pa,
            } => write!(
                f,
                "pressure limit: {name} {pressure_pa:.4e} Pa outside [{low_pa:.4e}, \
                 {high_pa:.4e}] Pa (from actuator.supply_pressure_pa)"
            ),
            Exceeded::NonFinite => write!(f, "the model state became non-finite"),
        }
    }
}

/// The first limit `state` breaks under `p`, in the order non-finite, stroke, velocity,
/// pressure; `None` inside the envelope.
pub fn check(p: &Params, state: &State) -> Option<Exceeded> {
    if state.iter().any(|x| !x.is_finite()) {
        return Some(Exceeded::NonFinite);
    }
    let (pa, pb) = match p.actuator.model {
        // P_L as the chamber difference, centred on P_s/2 as Hydraulics does
        ActuatorModel::Ideal => {
            let ps = p.actuator.supply_pressure_pa;
            (0.5 * (ps + state[ix::PA]), 0.5 * (ps - state[ix::PA]))
        }
        ActuatorModel::Nonlinear => (state[ix::PA], state[ix::PB]),
    };
    // the LVDT follows the actuator rod (free play, spec section 7), else the table
    let (x, v) = if p.free_play.enabled {
        (ix::XR, ix::VR)
    } else {
        (ix::X, ix::V)
    };
    let reading = Reading {
        displacement_m: state[x] - state[ix::XF],
        velocity_m_s: state[v] - state[ix::VF],
        pressure_a_pa: pa,
        pressure_b_pa: pb,
    };
    check_reading(p, &reading)
}

/// What the limits are checked on: the LVDT displacement, the speed relative to the
/// reaction mass and the chamber pressures (for the ideal actuator `P_a - P_b = P_L`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    pub displacement_m: f64,
    pub velocity_m_s: f64,
    pub pressure_a_pa: f64,
    pub pressure_b_pa: f64,
}

impl From<&Outputs> for Reading {
    fn from(o: &Outputs) -> Reading {
        Reading {
            displacement_m: o.displacement_m,
            velocity_m_s: o.velocity_m_s,
            pressure_a_pa: o.pressure_a_pa,
            pressure_b_pa: o.pressure_b_pa,
        }
    }
}

/// [`check`] on a [`Reading`] (a simulated sample's outputs, say).
pub fn check_reading(p: &Params, r: &Reading) -> Option<Exceeded> {
    let values = [
        r.displacement_m,
        r.velocity_m_s,
        r.pressure_a_pa,
        r.pressure_b_pa,
    ];
    if values.iter().any(|x| !x.is_finite()) {
        return Some(Exceeded::NonFinite);
    }
    let stroke = STROKE_FACTOR * p.limits.stroke_m;
    if r.displacement_m.abs() > stroke {
        return Some(Exceeded::Stroke {
            displacement_m: r.displacement_m,
            limit_m: stroke,
        });
    }
    let speed = VELOCITY_FACTOR * p.limits.velocity_m_s;
    if r.velocity_m_s.abs() > speed {
        return Some(Exceeded::Velocity {
            velocity_m_s: r.velocity_m_s,
            limit_m_s: speed,
        });
    }
    let ps = p.actuator.supply_pressure_pa;
    let high = PRESSURE_HIGH_FACTOR * ps;
    let outside = |name, pressure_pa: f64, low_pa: f64| {
        (pressure_pa < low_pa || pressure_pa > high).then_some(Exceeded::Pressure {
            name,
            pressure_pa,
            low_pa,
            high_pa: high,
        })
    };
    match p.actuator.model {
        ActuatorModel::Ideal => outside(
            "load pressure P_L",
            r.pressure_a_pa - r.pressure_b_pa,
            -high,
        ),
        ActuatorModel::Nonlinear => {
            let low = PRESSURE_LOW_FACTOR * ps;
            outside("chamber pressure P_a", r.pressure_a_pa, low)
                .or_else(|| outside("chamber pressure P_b", r.pressure_b_pa, low))
        }
    }
}

/// The first sample of a simulated record outside the envelope: its index and the limit.
pub fn first_exceeded(p: &Params, outputs: &[Outputs]) -> Option<(usize, Exceeded)> {
    outputs
        .iter()
        .enumerate()
        .find_map(|(k, o)| check_reading(p, &Reading::from(o)).map(|e| (k, e)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rest(p: &Params) -> State {
        super::super::Model::new(p).rest_state()
    }

    #[test]
    fn rest_is_inside_and_each_limit_is_named() {
        let mut p = Params::trees_lab();
        assert_eq!(check(&p, &rest(&p)), None);
        let mut s = rest(&p);
        s[ix::X] = 0.56; // 1.1 x 0.5 m = 0.55 m
        assert!(matches!(check(&p, &s), Some(Exceeded::Stroke { .. })));
        s[ix::XF] = 0.02; // the LVDT reads relative to the reaction mass
        assert_eq!(check(&p, &s), None);
        let mut s = rest(&p);
        s[ix::V] = -4.5; // 2 x 2.2 m/s = 4.4 m/s
        assert!(matches!(check(&p, &s), Some(Exceeded::Velocity { .. })));
        let mut s = rest(&p);
        s[ix::PA] = -31e6; // |P_L| > 1.1 x 28 MPa
        assert!(check(&p, &s).unwrap().to_string().contains("P_L"));
        p.actuator.model = ActuatorModel::Nonlinear;
        let mut s = rest(&p);
        s[ix::PB] = -3e6; // below -0.1 x 28 MPa
        assert!(check(&p, &s).unwrap().to_string().contains("P_b"));
        s[ix::PB] = f64::NAN;
        assert_eq!(check(&p, &s), Some(Exceeded::NonFinite));
    }
}
