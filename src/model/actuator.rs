//! Actuator and oil column (spec section 4) with the valve-side effects
//! `flow_saturation` and `valve_deadband` (spec section 7), whose physics lives in
//! [`crate::effects`].

use crate::effects::{flow_saturation, valve_deadband};
use crate::params::{ActuatorModel, Params};

/// Pressure scale of the smoothed signed root, Pa: `sr(p) = p / (p^2 + p0^2)^(1/4)`.
/// 0.1 MPa keeps the flow equations Lipschitz near zero pressure drop while changing
/// the root by less than 1e-5 relative at the operating drop `P_s/2`.
pub const SIGNED_ROOT_SCALE_PA: f64 = 1.0e5;

/// Smoothed signed square root (spec section 4).
#[inline]
pub fn signed_root(p: f64) -> f64 {
    p / (p * p + SIGNED_ROOT_SCALE_PA * SIGNED_ROOT_SCALE_PA)
        .sqrt()
        .sqrt()
}

#[derive(Debug, Clone, Copy)]
pub struct Hydraulics {
    pub model: ActuatorModel,
    pub area_m2: f64,
    pub volume_m3: f64,
    pub bulk_modulus_pa: f64,
    pub leakage: f64,
    pub flow_gain: f64,
    pub supply_pa: f64,
    /// Orifice coefficient `Kv = Kq / sr(P_s/2)`, so that the nonlinear actuator
    /// linearised at rest has exactly the flow gain Kq of the ideal one.
    pub orifice: f64,
    /// `4 beta / V_t`, the ideal actuator's pressure-rate coefficient.
    pub ideal_rate: f64,
    /// `Some(Q_max)` when flow saturation is on.
    pub max_flow: Option<f64>,
    /// Deadband d, 0 when off.
    pub deadband: f64,
    /// Flow factors for a positive and a negative spool (`flow_asymmetry`; 1 when off).
    pub direction: (f64, f64),
}

impl Hydraulics {
    pub fn new(p: &Params) -> Self {
        let a = &p.actuator;
        Hydraulics {
            model: a.model,
            area_m2: a.piston_area_m2,
            volume_m3: a.total_oil_volume_m3,
            bulk_modulus_pa: a.bulk_modulus_pa,
            leakage: a.leakage_m3_s_pa,
            flow_gain: a.flow_gain_m3_s,
            supply_pa: a.supply_pressure_pa,
            ideal_rate: a.pressure_rate_pa_m3(),
            orifice: a.flow_gain_m3_s / signed_root(a.supply_pressure_pa / 2.0),
            max_flow: p.flow_saturation.max_flow(),
            deadband: p.valve_deadband.band(),
            direction: p.flow_asymmetry.factors(),
        }
    }

    /// Spool opening that meters flow: zero inside the deadband, shifted outside it (spec 7).
    #[inline]
    pub fn metering_opening(&self, xv: f64) -> f64 {
        valve_deadband::metering_opening(self.deadband, xv)
    }

    #[inline]
    fn saturate(&self, q: f64) -> f64 {
        flow_saturation::saturate(self.max_flow, q)
    }

    /// Flows into chamber A and out of chamber B before flow saturation, m^3/s (the ideal
    /// actuator's one flow twice): the valve's metering, whose saturation edges and
    /// orifice branches are the actuator's switching surfaces.
    #[inline]
    pub fn valve_flows(&self, xv: f64, pa: f64, pb: f64) -> (f64, f64) {
        let opening = self.metering_opening(xv);
        let side = if opening >= 0.0 {
            self.direction.0
        } else {
            self.direction.1
        };
        match self.model {
            ActuatorModel::Ideal => {
                let q = self.flow_gain * opening * side;
                (q, q)
            }
            ActuatorModel::Nonlinear => {
                let s = opening.clamp(-1.0, 1.0); // spool clip
                let kv = self.orifice * side;
                if s >= 0.0 {
                    (
                        kv * s * signed_root(self.supply_pa - pa),
                        kv * s * signed_root(pb),
                    )
                } else {
                    (
                        kv * s * signed_root(pa),
                        kv * s * signed_root(self.supply_pa - pb),
                    )
                }
            }
        }
    }

    /// Chamber pressure rates `(P_a', P_b')` or, for the ideal actuator, `(P_L', 0)`.
    /// `pa`, `pb` are the pressure states (`pa` = P_L for the ideal actuator),
    /// `x_rel`, `v_rel` the piston stroke and velocity relative to the reaction mass.
    #[inline]
    pub fn pressure_rates(&self, xv: f64, pa: f64, pb: f64, x_rel: f64, v_rel: f64) -> (f64, f64) {
        let (qa, qb) = self.valve_flows(xv, pa, pb);
        let (qa, qb) = (self.saturate(qa), self.saturate(qb));
        let a = self.area_m2;
        match self.model {
            ActuatorModel::Ideal => {
                // (V_t / 4 beta) P_L' = Kq x_v - A v - C_l P_L
                let rate = self.ideal_rate * (qa - a * v_rel - self.leakage * pa);
                (rate, 0.0)
            }
            ActuatorModel::Nonlinear => {
                // chamber volumes, kept positive for strokes past the geometric end
                let half = 0.5 * self.volume_m3;
                let floor = 1e-3 * self.volume_m3;
                let va = (half + a * x_rel).max(floor);
                let vb = (half - a * x_rel).max(floor);
                let leak = self.leakage * (pa - pb);
                (
                    self.bulk_modulus_pa / va * (qa - a * v_rel - leak),
                    self.bulk_modulus_pa / vb * (-qb + a * v_rel + leak),
                )
            }
        }
    }

    /// Actuator force `F_A` from the pressure states.
    #[inline]
    pub fn force(&self, pa: f64, pb: f64) -> f64 {
        match self.model {
            ActuatorModel::Ideal => self.area_m2 * pa,
            ActuatorModel::Nonlinear => self.area_m2 * (pa - pb),
        }
    }

    /// Chamber pressures `(P_a, P_b)`; the ideal actuator splits P_L about `P_s/2`.
    #[inline]
    pub fn chamber_pressures(&self, pa: f64, pb: f64) -> (f64, f64) {
        match self.model {
            ActuatorModel::Ideal => (0.5 * (self.supply_pa + pa), 0.5 * (self.supply_pa - pa)),
            ActuatorModel::Nonlinear => (pa, pb),
        }
    }

    /// Pressure states at rest.
    pub fn rest_pressures(&self) -> (f64, f64) {
        match self.model {
            ActuatorModel::Ideal => (0.0, 0.0),
            ActuatorModel::Nonlinear => (0.5 * self.supply_pa, 0.5 * self.supply_pa),
        }
    }
}
