//! The physics of the table (spec sections 2-7): one derivative function over a fixed
//! state vector. It knows nothing of files, FMI or the command line.
//!
//! The state vector has a fixed layout whatever the configuration; states of blocks
//! that are switched off stay at zero with zero derivative. This keeps the hot path free
//! of allocation and lets the FMU serialise every configuration the same way.

pub mod actuator;
pub mod controller;
pub mod friction;
pub mod limits;
pub mod payload;
pub mod servovalve;
pub mod switching;

pub use controller::{Feedback, Reference};

use crate::effects::free_play::Contact;
use crate::effects::oscillator::Oscillator;
use crate::params::{Params, ServovalveModel};
use actuator::Hydraulics;
use friction::BoucWen;
use payload::Payload;
use servovalve::SpoolDynamics;

/// Number of states.
pub const NX: usize = 17;
/// The states of the bare table: spool, pressures, table and friction.
pub const CORE_STATES: usize = 7;
/// The state vector.
pub type State = [f64; NX];

/// Indices into [`State`].
pub mod ix {
    /// Spool position x_v (first/second-order valve).
    pub const XV: usize = 0;
    /// Spool velocity x_v' (second-order valve).
    pub const XV_DOT: usize = 1;
    /// Chamber pressure P_a (nonlinear) or load pressure P_L (ideal), Pa.
    pub const PA: usize = 2;
    /// Chamber pressure P_b (nonlinear), Pa.
    pub const PB: usize = 3;
    /// Absolute table displacement, m.
    pub const X: usize = 4;
    /// Absolute table velocity, m/s.
    pub const V: usize = 5;
    /// Bouc-Wen hysteretic variable Z.
    pub const Z: usize = 6;
    /// Absolute specimen displacement, m.
    pub const XS: usize = 7;
    /// Absolute specimen velocity, m/s.
    pub const VS: usize = 8;
    /// Reaction-mass displacement, m.
    pub const XF: usize = 9;
    /// Reaction-mass velocity, m/s.
    pub const VF: usize = 10;
    /// Absolute displacement of specimen mode 2, m (spec section 7, second part).
    pub const XS2: usize = 11;
    /// Absolute velocity of specimen mode 2, m/s.
    pub const VS2: usize = 12;
    /// Absolute displacement of specimen mode 3, m.
    pub const XS3: usize = 13;
    /// Absolute velocity of specimen mode 3, m/s.
    pub const VS3: usize = 14;
    /// Absolute actuator-rod displacement (free play), m.
    pub const XR: usize = 15;
    /// Absolute actuator-rod velocity (free play), m/s.
    pub const VR: usize = 16;
    /// Displacement and velocity states of the specimen's modes, mode 1 first.
    pub const SPECIMEN_MODES: [(usize, usize); 3] = [(XS, VS), (XS2, VS2), (XS3, VS3)];
}

/// Sensor noise on the controller's feedback channels at one instant (spec section 2).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SensorNoise {
    pub displacement_m: f64,
    pub acceleration_m_s2: f64,
    pub force_n: f64,
}

/// The inputs of the model at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Inputs {
    pub reference: Reference,
    /// Force applied to the table by a co-simulated body (FMU input), N.
    pub external_force_n: f64,
}

/// What the table's sensors would read (noise-free), and the controller's command.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Outputs {
    pub valve_command: f64,
    pub spool_position: f64,
    /// LVDT displacement relative to the reaction mass, m (with `free_play` the LVDT is
    /// on the actuator rod, spec section 7).
    pub displacement_m: f64,
    /// Table velocity relative to the reaction mass, m/s (with `free_play` the rod's, the
    /// derivative of the LVDT channel).
    pub velocity_m_s: f64,
    /// Absolute table acceleration, m/s^2.
    pub acceleration_m_s2: f64,
    pub actuator_force_n: f64,
    pub pressure_a_pa: f64,
    pub pressure_b_pa: f64,
}

/// The assembled model: every block's coefficients, computed once from [`Params`].
#[derive(Debug, Clone)]
pub struct Model {
    pub params: Params,
    pub valve: SpoolDynamics,
    pub hydraulics: Hydraulics,
    pub payload: Payload,
    pub friction: BoucWen,
    /// The specimen's mode 1 (the one-mode specimen).
    pub specimen: Oscillator,
    /// The specimen's modes 2 and 3 (each off unless present).
    pub specimen_modes: [Oscillator; 2],
    pub foundation: Oscillator,
    /// The free-play contact of actuator rod and table (spec section 7, second part).
    pub contact: Contact,
}

/// Forces and signals computed on the way to the derivatives.
#[derive(Debug, Clone, Copy, Default)]
pub struct Algebraic {
    pub valve_command: f64,
    /// The command before its clip to [-1, 1].
    pub command_before_clip: f64,
    pub spool_position: f64,
    pub actuator_force_n: f64,
    pub acceleration_m_s2: f64,
    /// Table displacement and velocity relative to the reaction mass (friction, stiffness).
    pub x_rel: f64,
    pub v_rel: f64,
    /// Piston stroke and its rate relative to the reaction mass: the LVDT and the flow
    /// equation's (the rod's with free play, else the table's `x_rel`, `v_rel`).
    pub stroke_m: f64,
    pub stroke_rate_m_s: f64,
    /// Force of the rod on the table through the free-play contact, N (0 when off).
    pub contact_force_n: f64,
}

impl Model {
    /// Assemble the model; the parameters must already be valid ([`Params::validate`]).
    pub fn new(p: &Params) -> Model {
        Model {
            params: *p,
            valve: SpoolDynamics::new(&p.servovalve),
            hydraulics: Hydraulics::new(p),
            payload: Payload::new(&p.table).without_rod(&p.free_play),
            friction: BoucWen::new(&p.friction, &p.stick_slip)
                .with_direction(&p.friction_asymmetry),
            specimen: p.specimen.oscillator(),
            specimen_modes: p.specimen.higher_oscillators(),
            foundation: p.foundation.oscillator(),
            contact: p.free_play.contact(),
        }
    }

    /// True when every state after the first [`CORE_STATES`] has a zero derivative
    /// (no specimen mode, free play or foundation).
    #[inline]
    pub fn core_only(&self) -> bool {
        !self.specimen.enabled
            && !self.specimen_modes.iter().any(|m| m.enabled)
            && !self.contact.enabled
            && !self.foundation.enabled
    }

    /// True when the spool is a pure delay of the command (needs the solver's history).
    pub fn has_delay(&self) -> bool {
        self.valve.model == ServovalveModel::Delay
    }

    /// Angular frequency of the free-play rod on its contact (rad/s), 0 without free play:
    /// the solver's sub-steps resolve it.
    pub fn contact_rate_rad_s(&self) -> f64 {
        if self.contact.enabled {
            let zeta = self.params.free_play.contact_damping_ratio;
            // the damped pole's modulus grows with the damping: w (zeta + sqrt(zeta^2 + 1))
            // bounds both eigenvalues of the rod-table pair
            self.contact.frequency_rad_s(self.params.table.mass_kg)
                * (zeta + (zeta * zeta + 1.0).sqrt())
        } else {
            0.0
        }
    }

    /// The table at rest: chambers at `P_s/2`, everything else zero.
    pub fn rest_state(&self) -> State {
        let mut s = [0.0; NX];
        let (pa, pb) = self.hydraulics.rest_pressures();
        s[ix::PA] = pa;
        s[ix::PB] = pb;
        s
    }

    /// Every signal that follows algebraically from the state and inputs: forces,
    /// acceleration, the controller's command (on noisy feedback) and the spool.
    /// `delayed_command` is `u(t - tau)` for the delay valve (ignored otherwise).
    #[inline(always)]
    pub fn algebraic(
        &self,
        s: &State,
        inp: &Inputs,
        noise: &SensorNoise,
        delayed_command: f64,
    ) -> Algebraic {
        let x_rel = s[ix::X] - s[ix::XF];
        let v_rel = s[ix::V] - s[ix::VF];
        let f_a = self.hydraulics.force(s[ix::PA], s[ix::PB]);
        let f_d = self.friction.force(s[ix::Z], v_rel);
        let f_e = self.payload.elastic_force(x_rel);
        let f_s = self.specimen_force(s);
        // free play (spec section 7): the actuator drives the rod, the contact the table
        let (stroke_m, stroke_rate_m_s, f_c) = if self.contact.enabled {
            let f_c = self
                .contact
                .force(s[ix::XR] - s[ix::X], s[ix::VR] - s[ix::V]);
            (s[ix::XR] - s[ix::XF], s[ix::VR] - s[ix::VF], f_c)
        } else {
            (x_rel, v_rel, 0.0)
        };
        let drive = if self.contact.enabled { f_c } else { f_a };
        let a = self
            .payload
            .acceleration(drive - f_d - f_e + f_s + inp.external_force_n);
        let feedback = Feedback {
            displacement_m: stroke_m + noise.displacement_m,
            velocity_m_s: stroke_rate_m_s,
            acceleration_m_s2: a + noise.acceleration_m_s2,
            force_n: f_a + noise.force_n,
        };
        let raw =
            controller::command_before_clip(&self.params.controller, &inp.reference, &feedback);
        let u = raw.clamp(-1.0, 1.0);
        let xv = match self.valve.model {
            ServovalveModel::Delay => self.valve.gain * delayed_command,
            _ => s[ix::XV],
        };
        Algebraic {
            valve_command: u,
            command_before_clip: raw,
            spool_position: xv,
            actuator_force_n: f_a,
            acceleration_m_s2: a,
            x_rel,
            v_rel,
            stroke_m,
            stroke_rate_m_s,
            contact_force_n: f_c,
        }
    }

    /// The force of the specimen's modes on the table (spec section 7): mode 1, then the
    /// present higher modes added (so a one-mode specimen computes exactly as before).
    #[inline(always)]
    fn specimen_force(&self, s: &State) -> f64 {
        if !self.specimen.enabled {
            return 0.0;
        }
        let mut f = -self
            .specimen
            .restoring_force(s[ix::XS] - s[ix::X], s[ix::VS] - s[ix::V]);
        for (m, &(xi, vi)) in self.specimen_modes.iter().zip(&ix::SPECIMEN_MODES[1..]) {
            if m.enabled {
                f -= m.restoring_force(s[xi] - s[ix::X], s[vi] - s[ix::V]);
            }
        }
        f
    }

    /// The derivative function `ds = f(s, inputs)`; returns the algebraic signals.
    /// Allocation-free: it is the solver's hot path.
    #[inline(always)]
    pub fn derivatives(
        &self,
        s: &State,
        inp: &Inputs,
        noise: &SensorNoise,
        delayed_command: f64,
        ds: &mut State,
    ) -> Algebraic {
        let alg = self.algebraic(s, inp, noise, delayed_command);
        // spool (section 3)
        let (dxv, dxv_dot) = self
            .valve
            .derivatives(alg.valve_command, s[ix::XV], s[ix::XV_DOT]);
        ds[ix::XV] = dxv;
        ds[ix::XV_DOT] = dxv_dot;
        // oil column (section 4)
        let (dpa, dpb) = self.hydraulics.pressure_rates(
            alg.spool_position,
            s[ix::PA],
            s[ix::PB],
            alg.stroke_m,
            alg.stroke_rate_m_s,
        );
        ds[ix::PA] = dpa;
        ds[ix::PB] = dpb;
        // table (section 5)
        ds[ix::X] = s[ix::V];
        ds[ix::V] = alg.acceleration_m_s2;
        // friction (eq. 4.15) on the stroke velocity
        ds[ix::Z] = self.friction.z_rate(s[ix::Z], alg.v_rel);
        // specimen (section 7): each mode on the table
        let modes = [
            &self.specimen,
            &self.specimen_modes[0],
            &self.specimen_modes[1],
        ];
        for (m, &(xi, vi)) in modes.into_iter().zip(&ix::SPECIMEN_MODES) {
            if m.enabled {
                ds[xi] = s[vi];
                ds[vi] = m.restoring_force(s[xi] - s[ix::X], s[vi] - s[ix::V]) / m.mass_kg;
            } else {
                ds[xi] = 0.0;
                ds[vi] = 0.0;
            }
        }
        // free play (section 7): the actuator pushes the rod, the contact pushes it back
        if self.contact.enabled {
            ds[ix::XR] = s[ix::VR];
            ds[ix::VR] = (alg.actuator_force_n - alg.contact_force_n) * self.contact.inv_rod_mass;
        } else {
            ds[ix::XR] = 0.0;
            ds[ix::VR] = 0.0;
        }
        // foundation (section 7): actuator, friction and stiffness push it back
        if self.foundation.enabled {
            let reaction = -(alg.actuator_force_n
                - self.friction.force(s[ix::Z], alg.v_rel)
                - self.payload.elastic_force(alg.x_rel));
            ds[ix::XF] = s[ix::VF];
            ds[ix::VF] = (reaction + self.foundation.restoring_force(s[ix::XF], s[ix::VF]))
                / self.foundation.mass_kg;
        } else {
            ds[ix::XF] = 0.0;
            ds[ix::VF] = 0.0;
        }
        alg
    }

    /// Sensor readings (noise-free) for a state; the command uses the noisy feedback.
    pub fn outputs(
        &self,
        s: &State,
        inp: &Inputs,
        noise: &SensorNoise,
        delayed_command: f64,
    ) -> Outputs {
        let alg = self.algebraic(s, inp, noise, delayed_command);
        let (pa, pb) = self.hydraulics.chamber_pressures(s[ix::PA], s[ix::PB]);
        Outputs {
            valve_command: alg.valve_command,
            spool_position: alg.spool_position,
            displacement_m: alg.stroke_m,
            velocity_m_s: alg.stroke_rate_m_s,
            acceleration_m_s2: alg.acceleration_m_s2,
            actuator_force_n: alg.actuator_force_n,
            pressure_a_pa: pa,
            pressure_b_pa: pb,
        }
    }

    /// Keep the state physical after a step: Bouc-Wen `Z` in [-1, 1] (section 5).
    #[inline]
    pub fn project(&self, s: &mut State) {
        s[ix::Z] = s[ix::Z].clamp(-1.0, 1.0);
    }
}
