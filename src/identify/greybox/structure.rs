//! Which parameters the closed-loop fit frees and which it fixes by convention, from what
//! the campaign states and what the section-4 estimators identified (issue 16, part 3).
//!
//! From the reference and the motion alone only combinations of the loop's parameters
//! are seen: the loop gain `Kp Ks Kq / A`, the feed-forward ratio `Fv Ks Kq / A`, the
//! oil column's frequency and damping, the valve's time constant and, without a force
//! channel, the friction per unit mass. One parameter of each combination is freed; the
//! others keep a stated value (the campaign's, an estimate, or a convention that is
//! listed as such, never a silent default).

use super::parameters::GreyParameter;
use crate::campaign::{Campaign, ControllerOverride, Measured};
use crate::params::{Params, ServovalveModel};
use serde::Serialize;

/// Supply pressure written when nobody gave it, Pa: the parameter rules' largest. The
/// ideal actuator's motion does not depend on it; it only bounds the load pressure,
/// whose scale here is a convention (the piston area and, without a force channel, the
/// mass), so a real table's load must not be refused for a conventional scale.
const SUPPLY_PRESSURE_CONVENTION_PA: f64 = 1e9;
const SUPPLY_PRESSURE_UNKNOWN: &str = "unknown: the ideal actuator's motion does not depend on it, and the load pressure's scale is a convention here; the rules' largest value, so that the envelope check does not refuse a real load on a conventional scale";

/// What is known before the closed-loop fit.
#[derive(Debug, Clone, Copy)]
pub struct Known {
    pub servovalve: bool,
    pub mass: bool,
    pub oil_column: bool,
    pub friction: bool,
}

/// A parameter held at a value the recordings cannot decide, with why.
#[derive(Debug, Clone, Serialize)]
pub struct Convention {
    pub key: &'static str,
    pub value: f64,
    pub reason: &'static str,
}

/// The structure of the fit: the free parameters and the conventions.
#[derive(Debug, Clone)]
pub struct Structure {
    pub free: Vec<GreyParameter>,
    pub conventions: Vec<Convention>,
    /// Whether a force channel takes part (then the mass is separable).
    pub with_force: bool,
}

const NOT_SEPARABLE_GEOMETRY: &str = "unknown, and not separable in the recorded motion: \
     only Kq/A, 4 beta A^2/V_t and C_l/A^2 enter it (value kept as the scale of the \
     identified combinations)";
const NOT_SEPARABLE_MASS: &str = "unknown, and without a force channel not separable \
     from the oil column's stiffness: only the oil-column frequency and the friction per \
     unit mass enter the motion (value kept as their scale)";
const GAIN_FIXED_ZERO: &str = "unknown, and not separable from the parameters the fit \
     frees (its effect on the motion is carried by them; the delta-P feedback's damping by \
     the leakage): zero";
const VALVE_FIRST_ORDER: &str = "no valve command and spool to identify the valve: the \
     first-order valve (paper eq. 4.1), whose time constant the fit frees, with unit gain \
     (the gain is not separable from the loop gain)";
const VALVE_SECOND_ORDER: &str = "no valve command and spool to identify the valve: the \
     second-order valve (paper eq. 4.2), whose natural frequency and damping the fit frees, \
     with unit gain (the gain is not separable from the loop gain); chosen over the \
     first-order valve because it follows the recorded motion better (see valve_order)";
const SHAPE_KEPT: &str = "the friction's Bouc-Wen shape is not separable from its \
     amplitude and yield in the motion: kept";
const YIELD_KEPT: &str = "without a force channel the friction's yield displacement is \
     not separable from its amplitude: kept";

/// The fit's structure for `p` (the section-4 results and the campaign's keys applied,
/// defaults elsewhere) on campaign `c`, whose tests `tests` take part.
pub fn choose(p: &mut Params, c: &Campaign, tests: &[usize], known: Known) -> Structure {
    let gains = &c.info.controller;
    let with_force = tests
        .iter()
        .any(|&i| c.records[i].measured(Measured::Force).is_some());
    let mut s = Structure {
        free: Vec::new(),
        conventions: Vec::new(),
        with_force,
    };
    s.free_the_loop_gains(p, c);
    s.zero_unknown_gains(p, gains);
    if !known.servovalve {
        s.free_the_valve(p);
    }
    if !known.oil_column {
        s.free
            .extend([GreyParameter::BulkModulus, GreyParameter::Leakage]);
    }
    if !known.mass {
        s.free_or_hold_the_mass(p, gains);
    }
    if !known.friction {
        s.free_the_friction(p);
    }
    s.hold_the_unknown_geometry(p, c);
    s
}

impl Structure {
    /// Hold parameter `key` at `value` for `reason`.
    fn hold(&mut self, key: &'static str, value: f64, reason: &'static str) {
        self.conventions.push(Convention { key, value, reason });
    }

    /// The loop gain (Kp if unknown, else the flow gain if unknown) and, if unknown, the
    /// velocity feed-forward (from zero).
    fn free_the_loop_gains(&mut self, p: &mut Params, c: &Campaign) {
        use GreyParameter::*;
        let gains = &c.info.controller;
        if gains.kp.is_none() {
            self.free.push(DisplacementGain);
        } else if c.info.geometry.flow_gain_m3_s.is_none() {
            self.free.push(FlowGain);
        }
        if gains.fv.is_none() {
            p.controller.fv = 0.0;
            self.free.push(VelocityFeedForward);
        }
    }

    /// The unknown gains the fit does not free (Kv, Ka, Fa, Kdp): zero, listed. Kdp's
    /// damping of the oil column is then carried by the leakage (the same flow per unit
    /// load pressure, without the valve's lag; freeing both left the loop gain in a
    /// valley of the cost on synthetic tables with a delta-P feedback).
    fn zero_unknown_gains(&mut self, p: &mut Params, gains: &ControllerOverride) {
        let k = &mut p.controller;
        for (key, given, slot) in [
            ("controller.kv", gains.kv, &mut k.kv),
            ("controller.ka", gains.ka, &mut k.ka),
            ("controller.fa", gains.fa, &mut k.fa),
            ("controller.kdp", gains.kdp, &mut k.kdp),
        ] {
            if given.is_none() {
                *slot = 0.0;
                self.hold(key, 0.0, GAIN_FIXED_ZERO);
            }
        }
    }

    /// A valve section 4 could not identify: first order with its time constant free,
    /// unit gain held.
    fn free_the_valve(&mut self, p: &mut Params) {
        p.servovalve.model = ServovalveModel::FirstOrder;
        p.servovalve.gain = 1.0;
        self.free.push(GreyParameter::ValveTimeConstant);
        self.hold("servovalve.gain", 1.0, VALVE_FIRST_ORDER);
    }

    /// An unknown mass: free where the motion separates it ([`mass_separable`]), else
    /// held as the scale.
    fn free_or_hold_the_mass(&mut self, p: &Params, gains: &ControllerOverride) {
        if mass_separable(self.with_force, gains) {
            self.free.push(GreyParameter::TableMass);
        } else {
            self.hold("table.mass_kg", p.table.mass_kg, NOT_SEPARABLE_MASS);
        }
    }

    /// Unknown friction: its force free, its shape held, its yield displacement free
    /// only with a force channel.
    fn free_the_friction(&mut self, p: &Params) {
        use GreyParameter::*;
        self.free.push(FrictionForce);
        self.hold("friction.shape", p.friction.shape, SHAPE_KEPT);
        if self.with_force {
            self.free.push(YieldDisplacement);
        } else {
            self.hold(
                "friction.yield_displacement_m",
                p.friction.yield_displacement_m,
                YIELD_KEPT,
            );
        }
    }

    /// The geometry the campaign does not give and the fit does not free: the supply
    /// pressure at its convention, the others at their values as the scale.
    fn hold_the_unknown_geometry(&mut self, p: &mut Params, c: &Campaign) {
        let g = &c.info.geometry;
        if g.supply_pressure_pa.is_none() {
            p.actuator.supply_pressure_pa = SUPPLY_PRESSURE_CONVENTION_PA;
            self.hold(
                "actuator.supply_pressure_pa",
                SUPPLY_PRESSURE_CONVENTION_PA,
                SUPPLY_PRESSURE_UNKNOWN,
            );
        }
        let geometry = [
            (
                "actuator.piston_area_m2",
                g.piston_area_m2,
                p.actuator.piston_area_m2,
            ),
            (
                "actuator.total_oil_volume_m3",
                g.total_oil_volume_m3,
                p.actuator.total_oil_volume_m3,
            ),
            (
                "actuator.flow_gain_m3_s",
                g.flow_gain_m3_s,
                p.actuator.flow_gain_m3_s,
            ),
        ];
        for (key, given, value) in geometry {
            let freed = self.free.iter().any(|f| f.key() == key);
            if given.is_none() && !freed {
                self.hold(key, value, NOT_SEPARABLE_GEOMETRY);
            }
        }
    }
}

/// Whether the motion separates the table mass from the oil column's stiffness: only
/// while something in the loop reads the force, a force channel or a known delta-P gain
/// (the command then holds `Kdp M a`). Otherwise the mass is a scale, held at a
/// convention (here and in the diagnosis).
pub fn mass_separable(with_force: bool, gains: &ControllerOverride) -> bool {
    with_force || gains.kdp.is_some_and(|k| k > 0.0)
}

impl Structure {
    /// The same fit with a second-order valve in place of the first-order one, and `p`
    /// (a first-order fit's result) turned into its start: unit damping and the natural
    /// frequency whose low-frequency lag `2 zeta / omega_n` is the time constant's.
    /// `None` when the valve is not free.
    pub fn with_second_order_valve(&self, p: &mut Params) -> Option<Structure> {
        use GreyParameter::*;
        let at = self.free.iter().position(|g| *g == ValveTimeConstant)?;
        let mut free = self.free.clone();
        free.splice(at..=at, [ValveNaturalFrequency, ValveDamping]);
        p.servovalve.model = ServovalveModel::SecondOrder;
        p.servovalve.damping_ratio = 1.0;
        p.servovalve.natural_frequency_hz =
            1.0 / (std::f64::consts::PI * p.servovalve.time_constant_s);
        let mut conventions = self.conventions.clone();
        for c in conventions
            .iter_mut()
            .filter(|c| c.key == "servovalve.gain")
        {
            c.reason = VALVE_SECOND_ORDER;
        }
        Some(Structure {
            free,
            conventions,
            with_force: self.with_force,
        })
    }
}
