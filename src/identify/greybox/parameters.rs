//! The physical parameters a closed-loop grey-box fit may free, by name, with how each is
//! searched (in logarithm for the positive scale parameters, linearly for those that may
//! be zero) and its physical bounds (the parameter file's own rules, `params::TABLE_RULES`).

use crate::params::Params;

/// A parameter of the closed loop (spec sections 2-5) the output-error fit may free.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GreyParameter {
    /// Displacement feedback Kp, 1/m (spec section 2): with the valve and flow gains it
    /// sets the loop gain `Kp Ks Kq / A`.
    DisplacementGain,
    /// The valve flow gain Kq, m^3/s: freed for the loop gain when Kp is known.
    FlowGain,
    /// Velocity feed-forward Fv, s/m.
    VelocityFeedForward,
    /// First-order servovalve time constant, s (paper eq. 4.1).
    ValveTimeConstant,
    /// Second-order servovalve natural frequency, Hz (paper eq. 4.2).
    ValveNaturalFrequency,
    /// Second-order servovalve damping ratio (paper eq. 4.2).
    ValveDamping,
    /// Effective bulk modulus, Pa: with the geometry and mass, the oil-column frequency.
    BulkModulus,
    /// Cross-port leakage, m^3/(s Pa): the oil column's damping.
    Leakage,
    /// Moving mass, kg: only separable from the oil column's stiffness with a force channel.
    TableMass,
    /// Bouc-Wen friction amplitude, N (eq. 4.14).
    FrictionForce,
    /// Bouc-Wen yield displacement, m (eq. 4.15).
    YieldDisplacement,
}

use GreyParameter::*;

impl GreyParameter {
    /// Every parameter a closed-loop fit may free.
    pub const ALL: [GreyParameter; 11] = [
        DisplacementGain,
        FlowGain,
        VelocityFeedForward,
        ValveTimeConstant,
        ValveNaturalFrequency,
        ValveDamping,
        BulkModulus,
        Leakage,
        TableMass,
        FrictionForce,
        YieldDisplacement,
    ];
}

/// Smallest leakage the fit searches, m^3/(s Pa): 1e-4 of the TREES Lab value's order,
/// a damping far below any measurable one (the logarithmic search needs a positive floor).
const LEAKAGE_FLOOR_M3_S_PA: f64 = 1e-16;
/// Largest leakage the fit searches: a ten-fold-overdamped oil column for any table the
/// parameter rules allow is far below this, so the bound only keeps the search finite.
const LEAKAGE_CEILING_M3_S_PA: f64 = 1e-5;
/// Servovalve time constants searched, s: from a 1.6 kHz valve to a 0.3 Hz one; real
/// servovalves lie between 2 ms and 50 ms.
const VALVE_TIME_CONSTANT_S: [f64; 2] = [1e-4, 0.5];
/// Second-order valve natural frequencies searched, Hz: the span of the time constants
/// under the second-order start's mapping `f_n = 1 / (pi tau)` (0.64 Hz to 3.2 kHz), and
/// a little beyond.
const VALVE_NATURAL_FREQUENCY_HZ: [f64; 2] = [0.3, 3300.0];
/// Second-order valve damping ratios searched: from a valve that rings (a 5-dB peak) to
/// one so overdamped that it is a first-order valve with a far pole. Real servovalves lie
/// between 0.5 and 1.5; a lightly damped "valve" is the fit mistaking it for the oil
/// column (measured: damping 0.08 at 16.5 Hz, with the oil column pushed to 24 Hz and
/// overdamped, on a short campaign of the TREES Lab table).
const VALVE_DAMPING: [f64; 2] = [0.3, 20.0];
/// Largest friction amplitude searched, N: ten times the largest actuators' force
/// (about 10 MN), so only the data bound it.
const FRICTION_CEILING_N: f64 = 1e8;
/// Largest velocity feed-forward searched, as a multiple of the full one `A / (Ks Kq)`
/// (which alone gives the reference velocity): twice, so a full feed-forward read high
/// in noise is inside the range.
pub const FEED_FORWARD_RATIO_BOUND: f64 = 2.0;
/// Displacement gains searched, 1/m: a loop gain from 1e-4 to 1e4 of the TREES Lab table's.
const DISPLACEMENT_GAIN_1_M: [f64; 2] = [1e-3, 1e5];

impl GreyParameter {
    /// The parameter-file key.
    pub fn key(self) -> &'static str {
        match self {
            DisplacementGain => "controller.kp",
            FlowGain => "actuator.flow_gain_m3_s",
            VelocityFeedForward => "controller.fv",
            ValveTimeConstant => "servovalve.time_constant_s",
            ValveNaturalFrequency => "servovalve.natural_frequency_hz",
            ValveDamping => "servovalve.damping_ratio",
            BulkModulus => "actuator.bulk_modulus_pa",
            Leakage => "actuator.leakage_m3_s_pa",
            TableMass => "table.mass_kg",
            FrictionForce => "friction.force_n",
            YieldDisplacement => "friction.yield_displacement_m",
        }
    }

    pub fn get(self, p: &Params) -> f64 {
        match self {
            DisplacementGain => p.controller.kp,
            FlowGain => p.actuator.flow_gain_m3_s,
            VelocityFeedForward => p.controller.fv,
            ValveTimeConstant => p.servovalve.time_constant_s,
            ValveNaturalFrequency => p.servovalve.natural_frequency_hz,
            ValveDamping => p.servovalve.damping_ratio,
            BulkModulus => p.actuator.bulk_modulus_pa,
            Leakage => p.actuator.leakage_m3_s_pa,
            TableMass => p.table.mass_kg,
            FrictionForce => p.friction.force_n,
            YieldDisplacement => p.friction.yield_displacement_m,
        }
    }

    pub fn set(self, p: &mut Params, value: f64) {
        let slot = match self {
            DisplacementGain => &mut p.controller.kp,
            FlowGain => &mut p.actuator.flow_gain_m3_s,
            VelocityFeedForward => &mut p.controller.fv,
            ValveTimeConstant => &mut p.servovalve.time_constant_s,
            ValveNaturalFrequency => &mut p.servovalve.natural_frequency_hz,
            ValveDamping => &mut p.servovalve.damping_ratio,
            BulkModulus => &mut p.actuator.bulk_modulus_pa,
            Leakage => &mut p.actuator.leakage_m3_s_pa,
            TableMass => &mut p.table.mass_kg,
            FrictionForce => &mut p.friction.force_n,
            YieldDisplacement => &mut p.friction.yield_displacement_m,
        };
        *slot = value;
    }

    /// Searched in logarithm: the positive scale parameters, whose plausible values span
    /// decades. The feed-forward and the friction may be zero and are searched linearly.
    pub fn logarithmic(self) -> bool {
        !matches!(self, VelocityFeedForward | FrictionForce)
    }

    /// Physical search bounds, given the rest of `p` (the feed-forward's and friction's
    /// scale follow from the geometry and the mass).
    pub fn bounds(self, p: &Params) -> [f64; 2] {
        let a = &p.actuator;
        match self {
            DisplacementGain => DISPLACEMENT_GAIN_1_M,
            FlowGain => [1e-6, 100.0],
            // up to twice the feed-forward that alone would give the reference velocity
            VelocityFeedForward => [
                0.0,
                FEED_FORWARD_RATIO_BOUND * a.piston_area_m2
                    / (a.flow_gain_m3_s * p.servovalve.gain),
            ],
            ValveTimeConstant => VALVE_TIME_CONSTANT_S,
            ValveNaturalFrequency => VALVE_NATURAL_FREQUENCY_HZ,
            ValveDamping => VALVE_DAMPING,
            BulkModulus => [1e7, 2e11],
            Leakage => [LEAKAGE_FLOOR_M3_S_PA, LEAKAGE_CEILING_M3_S_PA],
            TableMass => [0.1, 1e7],
            // a device between actuator and reaction (a damper) may push far more than
            // the moving mass weighs: the bound is the largest force the rules allow
            FrictionForce => [0.0, FRICTION_CEILING_N],
            YieldDisplacement => [1e-6, 1e-2],
        }
    }

    /// Typical magnitude of the search coordinate (for the finite-difference steps): one
    /// in logarithm (a relative change), the value's own size otherwise.
    pub fn search_scale(self, p: &Params) -> f64 {
        match self {
            VelocityFeedForward => self.bounds(p)[1] / 2.0,
            FrictionForce => self.get(p).abs().max(1.0),
            _ => 1.0,
        }
    }

    /// The search coordinate of `value`.
    pub fn to_search(self, value: f64) -> f64 {
        if self.logarithmic() {
            value.ln()
        } else {
            value
        }
    }

    /// The value of search coordinate `theta`.
    pub fn from_search(self, theta: f64) -> f64 {
        if self.logarithmic() {
            theta.exp()
        } else {
            theta
        }
    }
}

/// `p` with the free parameters set from search coordinates `theta`.
pub fn with_search(p: &Params, free: &[GreyParameter], theta: &[f64]) -> Params {
    let mut q = *p;
    for (g, t) in free.iter().zip(theta) {
        g.set(&mut q, g.from_search(*t));
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn search_coordinates_round_trip_and_bounds_hold_the_defaults() {
        let p = Params::trees_lab();
        for g in GreyParameter::ALL {
            let v = g.get(&p);
            let [lo, hi] = g.bounds(&p);
            assert!(v >= lo && v <= hi, "{}: {v} outside [{lo}, {hi}]", g.key());
            let back = g.from_search(g.to_search(v));
            assert!((back - v).abs() <= 1e-12 * v.abs(), "{}", g.key());
            let mut q = p;
            g.set(&mut q, 2.0 * v + 1e-3);
            assert_eq!(g.get(&q), 2.0 * v + 1e-3);
        }
    }
}
