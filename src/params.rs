//! Typed parameter blocks of the table model, their TREES Lab defaults (spec section 6),
//! TOML reading/writing and validation.
//!
//! A parameter file may hold only the keys that differ from the defaults; every missing
//! key takes its TREES Lab default. An unknown key is an error (it is nearly always a typo
//! that would otherwise be silently ignored).

use crate::effects::CATALOGUE;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Errors from reading or validating a parameter file.
#[derive(Debug, thiserror::Error)]
pub enum ParamsError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: String,
        source: std::io::Error,
    },
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    #[error("{file}: key `{key}` = {value}: {rule}")]
    Invalid {
        file: String,
        key: String,
        value: f64,
        rule: String,
    },
}

/// Three-variable controller gains (spec section 2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Controller {
    /// Displacement feedback Kp, 1/m.
    pub kp: f64,
    /// Velocity feedback Kv, s/m.
    pub kv: f64,
    /// Acceleration feedback Ka, s^2/m.
    pub ka: f64,
    /// Velocity feed-forward Fv, s/m.
    pub fv: f64,
    /// Acceleration feed-forward Fa, s^2/m.
    pub fa: f64,
    /// Delta-P (force) stabilisation Kdp, 1/N.
    pub kdp: f64,
}

impl Default for Controller {
    fn default() -> Self {
        Controller {
            kp: 10.0,
            kv: 0.0,
            ka: 0.0,
            fv: 0.4555,
            fa: 0.0,
            kdp: 3.293e-8,
        }
    }
}

/// Servovalve spool-dynamics variant (spec section 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ServovalveModel {
    Delay,
    FirstOrder,
    SecondOrder,
}

impl ServovalveModel {
    pub const ALL: [ServovalveModel; 3] = [
        ServovalveModel::Delay,
        ServovalveModel::FirstOrder,
        ServovalveModel::SecondOrder,
    ];
    pub fn name(self) -> &'static str {
        match self {
            ServovalveModel::Delay => "delay",
            ServovalveModel::FirstOrder => "first_order",
            ServovalveModel::SecondOrder => "second_order",
        }
    }
}

/// Servovalve parameters (spec section 3, paper eqs. 4.1-4.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Servovalve {
    pub model: ServovalveModel,
    /// Valve gain Ks (spool per unit command).
    pub gain: f64,
    /// Pure delay (`delay`) or time constant (`first_order`) tau, s.
    pub time_constant_s: f64,
    /// Natural frequency f_v of the `second_order` valve, Hz.
    pub natural_frequency_hz: f64,
    /// Damping ratio xi of the `second_order` valve.
    pub damping_ratio: f64,
}

impl Default for Servovalve {
    fn default() -> Self {
        Servovalve {
            model: ServovalveModel::SecondOrder,
            gain: 1.0,
            time_constant_s: 0.0137,
            natural_frequency_hz: 20.5,
            damping_ratio: 1.05,
        }
    }
}

/// Actuator variant (spec section 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActuatorModel {
    Ideal,
    Nonlinear,
}

impl ActuatorModel {
    pub const ALL: [ActuatorModel; 2] = [ActuatorModel::Ideal, ActuatorModel::Nonlinear];
    pub fn name(self) -> &'static str {
        match self {
            ActuatorModel::Ideal => "ideal",
            ActuatorModel::Nonlinear => "nonlinear",
        }
    }
}

/// Actuator, oil column and valve flow (spec section 4).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Actuator {
    pub model: ActuatorModel,
    /// Piston area A, m^2.
    pub piston_area_m2: f64,
    /// Total oil volume V_t of both chambers, m^3.
    pub total_oil_volume_m3: f64,
    /// Effective bulk modulus beta, Pa.
    pub bulk_modulus_pa: f64,
    /// Cross-port leakage coefficient C_l, m^3/(s Pa).
    pub leakage_m3_s_pa: f64,
    /// Valve flow gain Kq, m^3/s per unit spool.
    pub flow_gain_m3_s: f64,
    /// Supply pressure P_s, Pa.
    pub supply_pressure_pa: f64,
}

impl Default for Actuator {
    fn default() -> Self {
        Actuator {
            model: ActuatorModel::Ideal,
            piston_area_m2: 0.0911,
            total_oil_volume_m3: 0.12101,
            bulk_modulus_pa: 1.192e9,
            leakage_m3_s_pa: 1.5184e-10,
            flow_gain_m3_s: 0.2,
            supply_pressure_pa: 28.0e6,
        }
    }
}

impl Actuator {
    /// Oil-column stiffness k_oil = 4 beta A^2 / V_t (spec section 4), N/m.
    pub fn oil_column_stiffness_n_m(&self) -> f64 {
        4.0 * self.bulk_modulus_pa * self.piston_area_m2.powi(2) / self.total_oil_volume_m3
    }

    /// Bulk modulus giving the oil column `stiffness_n_m`: `k_oil V_t / (4 A^2)` (4.1.3), Pa.
    pub fn bulk_modulus_for_stiffness_pa(&self, stiffness_n_m: f64) -> f64 {
        stiffness_n_m * self.total_oil_volume_m3 / (4.0 * self.piston_area_m2 * self.piston_area_m2)
    }

    /// Bulk modulus putting the oil column of mass `mass_kg` at `frequency_hz` (4.1.3), Pa.
    pub fn bulk_modulus_for_frequency_pa(&self, frequency_hz: f64, mass_kg: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * frequency_hz;
        self.bulk_modulus_for_stiffness_pa(w.powi(2) * mass_kg)
    }

    /// Oil-column damping ratio `(C_l / A) sqrt(beta M / V_t)`, mass `mass_kg` (spec 4).
    pub fn oil_column_damping_ratio(&self, mass_kg: f64) -> f64 {
        self.leakage_m3_s_pa / self.piston_area_m2 * self.damping_scale(mass_kg)
    }

    /// Leakage giving `damping_ratio` at mass `mass_kg`: `zeta A / sqrt(beta M / V_t)`.
    pub fn leakage_for_damping_ratio_m3_s_pa(&self, mass_kg: f64, damping_ratio: f64) -> f64 {
        damping_ratio * self.piston_area_m2 / self.damping_scale(mass_kg)
    }

    /// `sqrt(beta M / V_t)`: the oil column's damping ratio per unit `C_l / A`.
    fn damping_scale(&self, mass_kg: f64) -> f64 {
        (self.bulk_modulus_pa * mass_kg / self.total_oil_volume_m3).sqrt()
    }

    /// `4 beta / V_t`: the ideal actuator's load-pressure rate per unit flow, Pa/m^3.
    pub fn pressure_rate_pa_m3(&self) -> f64 {
        4.0 * self.bulk_modulus_pa / self.total_oil_volume_m3
    }
}

/// Rigid table (payload) mass and horizontal stiffness (spec section 5).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Table {
    /// Rigid moving mass M, kg.
    pub mass_kg: f64,
    /// Horizontal stiffness k_h, N/m.
    pub stiffness_n_m: f64,
}

impl Default for Table {
    fn default() -> Self {
        Table {
            mass_kg: 41_258.0,
            stiffness_n_m: 0.0,
        }
    }
}

/// Bouc-Wen viscoplastic friction (paper eqs. 4.14-4.15).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Friction {
    /// Friction amplitude F_mu, N.
    pub force_n: f64,
    /// Equivalent yield displacement Y, m.
    pub yield_displacement_m: f64,
    /// Dimensionless shape constant b, in [0, 1): at b = 1 a saturated Z can never
    /// leave +-1 again (eq. 4.15 has a fixed point there), so reversals would stick.
    pub shape: f64,
}

impl Default for Friction {
    fn default() -> Self {
        Friction {
            force_n: 4000.0,
            yield_displacement_m: 1e-3,
            shape: 0.5,
        }
    }
}

pub use crate::effects::flow_asymmetry::FlowAsymmetry;
pub use crate::effects::flow_saturation::FlowSaturation;
pub use crate::effects::foundation::Foundation;
pub use crate::effects::free_play::FreePlay;
pub use crate::effects::friction_asymmetry::FrictionAsymmetry;
pub use crate::effects::specimen::Specimen;
pub use crate::effects::stick_slip::StickSlip;
pub use crate::effects::valve_deadband::ValveDeadband;

/// Operating limits (spec section 8): the table's envelope. A run that leaves it
/// describes nothing real (a real table's end stops, relief valves and interlocks act
/// first), so the solver stops it with an error naming the time and the limit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Limits {
    /// Stroke, m: the LVDT displacement may not exceed 1.1 times it.
    pub stroke_m: f64,
    /// Velocity limit, m/s: the table's speed relative to the reaction mass may not
    /// exceed twice it.
    pub velocity_m_s: f64,
}

impl Default for Limits {
    fn default() -> Self {
        // TREES Lab, paper section 2: +-0.5 m stroke, 2.2 m/s peak velocity
        Limits {
            stroke_m: 0.5,
            velocity_m_s: 2.2,
        }
    }
}

/// Every parameter of the table model: one block per part of the spec.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct Params {
    pub controller: Controller,
    pub servovalve: Servovalve,
    pub actuator: Actuator,
    pub table: Table,
    pub friction: Friction,
    pub specimen: Specimen,
    pub foundation: Foundation,
    pub stick_slip: StickSlip,
    pub flow_saturation: FlowSaturation,
    pub valve_deadband: ValveDeadband,
    pub friction_asymmetry: FrictionAsymmetry,
    pub flow_asymmetry: FlowAsymmetry,
    pub free_play: FreePlay,
    pub limits: Limits,
}

/// Names of the catalogue effects (spec section 7), in catalogue order.
pub const EFFECTS: [&str; CATALOGUE.len()] = effect_names();

const fn effect_names() -> [&'static str; CATALOGUE.len()] {
    let mut names = [""; CATALOGUE.len()];
    let mut i = 0;
    while i < CATALOGUE.len() {
        names[i] = CATALOGUE[i].name;
        i += 1;
    }
    names
}

impl Params {
    /// TREES Lab defaults (spec section 6).
    pub fn trees_lab() -> Params {
        Params::default()
    }

    /// Parse TOML text; `file` names the source in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Params, ParamsError> {
        let p: Params = toml::from_str(text).map_err(|e| ParamsError::Parse {
            file: file.to_string(),
            message: e.to_string().trim_end().replace('\n', "\n  "),
        })?;
        p.validate_in(file)?;
        Ok(p)
    }

    /// Read and validate a parameter file.
    pub fn from_file(path: &Path) -> Result<Params, ParamsError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ParamsError::Io {
            file: file.clone(),
            source,
        })?;
        Params::from_toml_str(&text, &file)
    }

    /// The complete parameter set as TOML (every key written).
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).expect("parameters always serialise to TOML")
    }

    /// Validate with `<memory>` as the source name.
    pub fn validate(&self) -> Result<(), ParamsError> {
        self.validate_in("<parameters>")
    }

    /// Check every physical rule; the first broken one is reported with its dotted key.
    pub fn validate_in(&self, file: &str) -> Result<(), ParamsError> {
        for (key, value) in self.numeric_entries() {
            if !value.is_finite() {
                return Err(invalid(file, key, value, "must be a finite number"));
            }
        }
        let values: std::collections::HashMap<&str, f64> =
            self.numeric_entries().into_iter().collect();
        let mut rules: Vec<(&str, f64, Rule)> = TABLE_RULES
            .iter()
            .map(|&(key, rule)| (key, values[key], rule))
            .collect();
        let c = &self.servovalve;
        for (key, rule) in servovalve_rules(c.model) {
            rules.push((key, values[key], rule));
        }
        for effect in CATALOGUE.iter().filter(|e| e.is_enabled(self)) {
            for q in effect.all_parameters() {
                rules.push((q.dotted_key, (q.read)(self), q.rule));
            }
        }
        for (key, value, rule) in rules {
            if let Some(text) = rule.broken_by(value) {
                return Err(invalid(file, key, value, &text));
            }
        }
        // rules across parameters, once each parameter keeps its own
        for effect in CATALOGUE.iter().filter(|e| e.is_enabled(self)) {
            if let Some(b) = effect.cross_check.and_then(|check| check(self)) {
                return Err(invalid(file, b.key, b.value, &b.rule));
            }
        }
        Ok(())
    }

    /// Every numeric parameter with its dotted TOML key (for checks and reports).
    pub fn numeric_entries(&self) -> Vec<(&'static str, f64)> {
        let k = &self.controller;
        let s = &self.servovalve;
        let a = &self.actuator;
        let mut entries = vec![
            ("controller.kp", k.kp),
            ("controller.kv", k.kv),
            ("controller.ka", k.ka),
            ("controller.fv", k.fv),
            ("controller.fa", k.fa),
            ("controller.kdp", k.kdp),
            ("servovalve.gain", s.gain),
            ("servovalve.time_constant_s", s.time_constant_s),
            ("servovalve.natural_frequency_hz", s.natural_frequency_hz),
            ("servovalve.damping_ratio", s.damping_ratio),
            ("actuator.piston_area_m2", a.piston_area_m2),
            ("actuator.total_oil_volume_m3", a.total_oil_volume_m3),
            ("actuator.bulk_modulus_pa", a.bulk_modulus_pa),
            ("actuator.leakage_m3_s_pa", a.leakage_m3_s_pa),
            ("actuator.flow_gain_m3_s", a.flow_gain_m3_s),
            ("actuator.supply_pressure_pa", a.supply_pressure_pa),
            ("table.mass_kg", self.table.mass_kg),
            ("table.stiffness_n_m", self.table.stiffness_n_m),
            ("friction.force_n", self.friction.force_n),
            (
                "friction.yield_displacement_m",
                self.friction.yield_displacement_m,
            ),
            ("friction.shape", self.friction.shape),
        ];
        for effect in &CATALOGUE {
            for q in effect.all_parameters() {
                entries.push((q.dotted_key, (q.read)(self)));
            }
        }
        entries.push(("limits.stroke_m", self.limits.stroke_m));
        entries.push(("limits.velocity_m_s", self.limits.velocity_m_s));
        entries
    }

    /// Switch on a catalogue effect and set its parameters from `key=value` pairs
    /// (the `--effect specimen:mass_kg=20000,frequency_hz=6` syntax of the command line).
    pub fn apply_effect_spec(&mut self, spec: &str) -> Result<(), String> {
        let (name, rest) = match spec.split_once(':') {
            Some((n, r)) => (n.trim(), r.trim()),
            None => (spec.trim(), ""),
        };
        let effect = crate::effects::by_name(name).ok_or_else(|| {
            format!(
                "unknown effect `{name}` in `{spec}`; known effects: {}",
                EFFECTS.join(", ")
            )
        })?;
        let mut p = *self;
        effect.apply_pairs(&mut p, rest, spec)?;
        p.validate_in(&format!("--effect {spec}"))
            .map_err(|e| e.to_string())?;
        *self = p;
        Ok(())
    }
}

/// The validation rule of every parameter of the table itself (the effects declare theirs
/// in the catalogue, the servovalve's depend on its model: [`servovalve_rules`]). Read by
/// [`Params::validate_in`] and by the FMU's `min`/`max` ([`fmu_rule_of`]).
pub const TABLE_RULES: &[(&str, Rule)] = &[
    // a TVC loop's gains are positive or off: a negative one turns feedback into
    // positive feedback (or the feed-forward against the motion)
    ("controller.kp", Rule::NonNegative),
    ("controller.kv", Rule::NonNegative),
    ("controller.ka", Rule::NonNegative),
    ("controller.fv", Rule::NonNegative),
    ("controller.fa", Rule::NonNegative),
    ("controller.kdp", Rule::NonNegative),
    ("servovalve.gain", Rule::Positive),
    ("actuator.piston_area_m2", PISTON_AREA_M2),
    ("actuator.total_oil_volume_m3", OIL_VOLUME_M3),
    ("actuator.bulk_modulus_pa", BULK_MODULUS_PA),
    ("actuator.leakage_m3_s_pa", Rule::NonNegative),
    ("actuator.flow_gain_m3_s", FLOW_GAIN_M3_S),
    ("actuator.supply_pressure_pa", SUPPLY_PRESSURE_PA),
    ("table.mass_kg", TABLE_MASS_KG),
    ("table.stiffness_n_m", Rule::NonNegative),
    ("friction.force_n", Rule::NonNegative),
    ("friction.yield_displacement_m", YIELD_DISPLACEMENT_M),
    ("friction.shape", Rule::HalfOpenUnit),
    ("limits.stroke_m", Rule::Positive),
    ("limits.velocity_m_s", Rule::Positive),
];

/// The servovalve's rules for its model (spec section 3): a delay may be zero, a time
/// constant may not; the second-order keys are checked only for that model.
pub fn servovalve_rules(model: ServovalveModel) -> Vec<(&'static str, Rule)> {
    match model {
        ServovalveModel::Delay => vec![("servovalve.time_constant_s", Rule::NonNegative)],
        ServovalveModel::FirstOrder => vec![("servovalve.time_constant_s", Rule::Positive)],
        ServovalveModel::SecondOrder => vec![
            ("servovalve.natural_frequency_hz", Rule::Positive),
            ("servovalve.damping_ratio", Rule::NonNegative),
        ],
    }
}

/// The rule of the parameter `key` that holds whatever the structural choices are (the
/// loosest over the servovalve models): the FMU declares it as `min`/`max`.
pub fn fmu_rule_of(key: &str) -> Option<Rule> {
    let servovalve = [
        ServovalveModel::Delay,
        ServovalveModel::FirstOrder,
        ServovalveModel::SecondOrder,
    ];
    TABLE_RULES
        .iter()
        .map(|&(k, r)| (k, r))
        .chain(servovalve.iter().flat_map(|&m| servovalve_rules(m)))
        .chain(
            CATALOGUE
                .iter()
                .flat_map(|e| e.all_parameters().map(|q| (q.dotted_key, q.rule))),
        )
        .filter(|&(k, _)| k == key)
        .map(|(_, r)| r)
        .reduce(Rule::loosest)
}

fn invalid(file: &str, key: &str, value: f64, rule: &str) -> ParamsError {
    ParamsError::Invalid {
        file: file.to_string(),
        key: key.to_string(),
        value,
        rule: rule.to_string(),
    }
}

/// A validation rule of one parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rule {
    Positive,
    NonNegative,
    HalfOpenUnit,
    AtLeastOne,
    /// A physical range `[min, max]`, inclusive, with why these bounds.
    Range {
        min: f64,
        max: f64,
        why: &'static str,
    },
}

/// Piston area: 1 mm^2 (a 1.1 mm bore) to 10 m^2 (a 3.6 m bore); TREES Lab 0.0911 m^2,
/// the largest tables' actuators about 0.2 m^2. Beyond it the oil-column stiffness
/// `4 beta A^2 / V_t` over- or underflows in parameter files.
pub const PISTON_AREA_M2: Rule = Rule::Range {
    min: 1e-6,
    max: 10.0,
    why: "from a 1.1 mm bore to a 3.6 m bore",
};
/// Total oil volume: a few cm^3 (a small actuator) to 100 m^3 (far above any table).
pub const OIL_VOLUME_M3: Rule = Rule::Range {
    min: 1e-6,
    max: 100.0,
    why: "from a few cm^3 to far above any table",
};
/// Effective bulk modulus: heavily aerated oil (1e7 Pa) to steel (2e11 Pa).
pub const BULK_MODULUS_PA: Rule = Rule::Range {
    min: 1e7,
    max: 2e11,
    why: "from aerated oil to steel",
};
/// Valve flow gain: a 1 cm^3/s micro-valve to 100 m^3/s (fifty times the largest tables).
pub const FLOW_GAIN_M3_S: Rule = Rule::Range {
    min: 1e-6,
    max: 100.0,
    why: "from a micro-valve to fifty times the largest tables",
};
/// Supply pressure: 1 bar to 1 GPa (hydraulics run at 7-70 MPa).
pub const SUPPLY_PRESSURE_PA: Rule = Rule::Range {
    min: 1e5,
    max: 1e9,
    why: "from 1 bar to 10 kbar",
};
/// Table mass: a 100 g shaker armature to 10 000 t (E-Defense moves about 1 200 t).
pub const TABLE_MASS_KG: Rule = Rule::Range {
    min: 0.1,
    max: 1e7,
    why: "from a shaker armature to 10 000 t",
};
/// Bouc-Wen yield displacement Y (eq. 4.15). Below 1 um the pre-sliding branch lies under
/// any table LVDT's resolution (16 bits over +-0.5 m: 15 um), so it cannot be identified
/// and the friction is Coulomb-like anyway; and the solver's sub-step guard needs
/// `2 |v| dt / Y` sub-steps per interval (at 1 um and 2.2 m/s, 8 600 per 1/512-s sample,
/// about 1 000 times the usual): a yield of 1e-9 m turned a 22-s run into minutes.
pub const YIELD_DISPLACEMENT_M: Rule = Rule::Range {
    min: 1e-6,
    max: 1.0,
    why: "below 1 um the pre-sliding branch is finer than any LVDT resolves and costs \
          the solver millions of sub-steps",
};

impl Rule {
    /// The inclusive bounds an FMU can declare: `Positive` becomes `min = 0` (FMI bounds
    /// are inclusive; the FMU itself refuses 0 at initialization).
    pub fn bounds(self) -> (Option<f64>, Option<f64>) {
        match self {
            Rule::Positive | Rule::NonNegative => (Some(0.0), None),
            Rule::HalfOpenUnit => (Some(0.0), Some(1.0)),
            Rule::AtLeastOne => (Some(1.0), None),
            Rule::Range { min, max, .. } => (Some(min), Some(max)),
        }
    }

    /// Of two rules of one key, the one that allows more (`NonNegative` over `Positive`).
    fn loosest(self, other: Rule) -> Rule {
        match (self, other) {
            (Rule::Positive, Rule::NonNegative) => other,
            _ => self,
        }
    }

    /// `None` when `v` satisfies the rule, else the rule in words.
    pub fn broken_by(self, v: f64) -> Option<String> {
        let ok = match self {
            Rule::Positive => v > 0.0,
            Rule::NonNegative => v >= 0.0,
            Rule::HalfOpenUnit => (0.0..1.0).contains(&v),
            Rule::AtLeastOne => v >= 1.0,
            Rule::Range { min, max, .. } => (min..=max).contains(&v),
        };
        if ok {
            return None;
        }
        Some(match self {
            Rule::Positive => "must be > 0".into(),
            Rule::NonNegative => "must be >= 0".into(),
            Rule::HalfOpenUnit => "must be in [0, 1)".into(),
            Rule::AtLeastOne => "must be >= 1".into(),
            Rule::Range { min, max, why } => format!("must be in [{min:e}, {max:e}] ({why})"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_match_spec_section_6() {
        let p = Params::trees_lab();
        // V_t = 4 beta A^2 / (M (2 pi f_oil)^2) with f_oil = 14.169 Hz (spec section 6)
        let w = 2.0 * std::f64::consts::PI * 14.169;
        let vt = 4.0 * p.actuator.bulk_modulus_pa * p.actuator.piston_area_m2.powi(2)
            / (p.table.mass_kg * w * w);
        assert!((vt / p.actuator.total_oil_volume_m3 - 1.0).abs() < 1e-4);
        // zeta_oil = (C_l/A) sqrt(beta M / V_t) = 0.0336
        let z = p.actuator.leakage_m3_s_pa / p.actuator.piston_area_m2
            * (p.actuator.bulk_modulus_pa * p.table.mass_kg / p.actuator.total_oil_volume_m3)
                .sqrt();
        assert!((z - 0.0336).abs() < 2e-4, "zeta_oil {z}");
        // Fv = A / Kq, Kdp = 3e-9 / A
        assert!((p.controller.fv - 0.0911 / 0.2).abs() < 1e-12);
        assert!((p.controller.kdp - 3e-9 / 0.0911).abs() < 1e-11);
    }

    #[test]
    fn toml_round_trip() {
        let p = Params::trees_lab();
        let q = Params::from_toml_str(&p.to_toml_string(), "x").unwrap();
        assert_eq!(p, q);
    }

    #[test]
    fn partial_file_takes_defaults() {
        let p = Params::from_toml_str("[table]\nmass_kg = 50000.0\n", "lab.toml").unwrap();
        assert_eq!(p.table.mass_kg, 50000.0);
        assert_eq!(p.actuator, Actuator::default());
    }

    #[test]
    fn bad_values_name_file_key_and_rule() {
        let e = Params::from_toml_str("[table]\nmass_kg = -1.0\n", "lab.toml").unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("lab.toml")
                && m.contains("table.mass_kg")
                && m.contains("must be in [1e-1, 1e7]"),
            "{m}"
        );
        let e = Params::from_toml_str(
            "[valve_deadband]\nenabled = true\ndeadband = 1.0\n",
            "lab.toml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("[0, 1)"), "{e}");
        let e = Params::from_toml_str("[table]\nmas_kg = 1.0\n", "lab.toml").unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("lab.toml") && m.contains("mas_kg") && m.contains("line 2"),
            "{m}"
        );
        let e = Params::from_toml_str("[friction]\nshape = 2.0\n", "f.toml").unwrap_err();
        assert!(e.to_string().contains("friction.shape"), "{e}");
        let e = Params::from_toml_str("[servovalve]\nmodel = \"third\"\n", "f.toml").unwrap_err();
        assert!(e.to_string().contains("third"), "{e}");
    }

    #[test]
    fn effect_spec_parses_and_validates() {
        let mut p = Params::trees_lab();
        p.apply_effect_spec("specimen:mass_kg=20000,frequency_hz=6,damping_ratio=0.02")
            .unwrap();
        assert!(p.specimen.enabled);
        assert_eq!(p.specimen.mass_kg, 20000.0);
        assert_eq!(p.specimen.frequency_hz, 6.0);
        assert!(p.apply_effect_spec("specimen:mass=1").is_err());
        assert!(p.apply_effect_spec("wobble:x=1").is_err());
        assert!(p.apply_effect_spec("valve_deadband:deadband=1.5").is_err());
    }
}
