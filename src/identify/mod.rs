//! Identification of the model parameters from a campaign (paper section 4), automatic:
//! every estimator takes the tests it needs by kind and content ([`select`]: a lab names
//! its tests as it likes), and a missing test or channel is reported, not failed.
//!
//! Order (each step uses the earlier ones): servovalve from the valve test (4.1.1,
//! [`servovalve`]); stiffness and sliding friction from the triangles (4.2.1,
//! [`friction`]); rigid mass from the mass test (4.1.2, [`mass`]); Bouc-Wen friction from
//! the slow sines (4.2.3, eqs. 4.13-4.15); mass by the loop approach from the fast sines
//! (4.2.2, [`periodic`]); oil column from the oil-column test (4.1.3, [`oil_column`]);
//! validation of the table TF (section 5, [`validation`]). On the paper's program these
//! are R1, T1-T6, R2, S1/S2/S4/S5/S7/S8, S3/S6/S9, R3 and R2. Without a random test's
//! mass, friction and mass come from the sines together ([`periodic`]). Apart: a device
//! between actuator and reaction from any test with displacement and force ([`device`]).
//! The device fit and the comparison of the identified model with every test are asked
//! for ([`Scope::Complete`], the `identify` command); the diagnosis takes the parameters
//! only ([`identify_screened`]).

mod chain;
mod device;
mod error;
mod estimates;
pub mod frf;
mod friction;
pub mod greybox;
pub mod lsq;
mod mass;
mod mass_mode;
mod missing;
mod oil_column;
mod periodic;
mod results;
pub mod select;
mod servovalve;
pub(crate) mod signals;
pub mod spool;
mod validation;

pub use chain::identify_screened_with;
pub use device::fit_device;
pub use error::IdentifyError;
pub use estimates::{Estimate, Quantity};
pub use friction::{bouc_wen_path, fit_friction, fit_triangles};
pub(crate) use mass::carried_modes_text;
pub use mass::{apparent_mass_less_friction, fit_mass, fit_mass_corrected};
pub use mass_mode::{fit_table_with_modes, CarriedMode, TableWithModes};
pub use missing::{Estimation, Missing};
pub use oil_column::{fit_oil_column, ColumnMass, OilColumnInput, OilGeometry};
pub use periodic::{fit_friction_and_mass, fit_mass_periodic};
pub use results::*;
pub use servovalve::{fit_servovalve, relative_error};
pub use validation::validate;

use crate::campaign::screen::{screen, Screening};
use crate::campaign::{Campaign, Record};
use crate::linear::OilColumn;

/// Frequency resolution of the Welch estimates, Hz (Hann, 50 % overlap).
pub const RESOLUTION_HZ: f64 = 0.25;
/// Band of the servovalve fits (paper Figure 4).
pub const VALVE_BAND_HZ: [f64; 2] = [0.5, 50.0];
/// Band of the apparent-mass fit (mass, viscous and stiffness-like terms).
pub const MASS_BAND_HZ: [f64; 2] = [2.0, 20.0];
/// Band of the oil-column fit.
pub const OIL_BAND_HZ: [f64; 2] = [4.0, 40.0];
/// Band of the validation error.
pub const VALIDATION_BAND_HZ: [f64; 2] = [1.0, 40.0];
/// Triangles: samples with |u| below this fraction of the amplitude (eq. 4.9).
pub const TRIANGLE_FRACTION: f64 = 0.8;
/// Shortest random record for a spectral estimate (R1, R2, R3), seconds: eight 50 %
/// overlapped Welch segments of 2 s (0.5 Hz resolution, coarser cannot place the valve
/// and oil-column corners; fewer averages leave an FRF variance above 1/8).
pub const MIN_RANDOM_S: f64 = 9.0;
/// Fewest steady cycles of a sine (between its first and last full-amplitude peaks) for
/// the loop approach and the Bouc-Wen fit: pairing `t` with `T/2 - t` needs one whole
/// cycle, and the hysteresis loop is only closed over one.
pub const MIN_SINE_CYCLES: f64 = 1.0;
/// Fewest steady cycles over all triangle tests (both directions of sliding needed).
pub const MIN_TRIANGLE_CYCLES: f64 = 1.0;
/// Physical bounds of a table's moving mass, kg: from a bench table to the largest
/// tables with payload (about 2000 t).
pub const MASS_BOUNDS_KG: [f64; 2] = [1.0, 2e6];
/// Physical bounds of the servovalve's and oil column's natural frequencies, Hz.
pub const FREQUENCY_BOUNDS_HZ: [f64; 2] = [0.1, 2000.0];
/// Physical bounds of a damping ratio.
pub const DAMPING_BOUNDS: [f64; 2] = [0.0, 10.0];

/// `Err` naming `what` of test `name` unless `x` is finite and within `bounds`.
fn check_bounds(name: &str, what: &str, x: f64, bounds: [f64; 2]) -> Result<(), IdentifyError> {
    if x.is_finite() && x >= bounds[0] && x <= bounds[1] {
        Ok(())
    } else {
        Err(IdentifyError::OutOfBounds {
            test: name.to_string(),
            what: what.to_string(),
            value: x,
            bounds,
        })
    }
}

/// `Err` naming test `name` unless the record lasts `MIN_RANDOM_S`.
fn check_random_length(name: &str, rec: &Record, fs: f64, what: &str) -> Result<(), IdentifyError> {
    let secs = rec.len() as f64 / fs;
    if secs >= MIN_RANDOM_S {
        Ok(())
    } else {
        Err(IdentifyError::TooShort {
            test: name.to_string(),
            seconds: secs,
            what: what.to_string(),
            min_s: MIN_RANDOM_S,
        })
    }
}

/// `Err` when a nonlinear fit did not move from its start (it would report the start).
fn check_moved(
    name: &str,
    what: &str,
    fit: &lsq::LsqFit,
    t0: &[f64],
    scale: &[f64],
) -> Result<(), IdentifyError> {
    if fit.moved_from(t0, scale) {
        Ok(())
    } else {
        Err(IdentifyError::DidNotMove {
            test: name.to_string(),
            what: what.to_string(),
        })
    }
}

/// How much an identification computes beyond the model's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// The parameters and their estimates only, what the diagnosis needs: no device fit,
    /// and no comparison of the model with every test unless the closed-loop fit made one.
    Parameters,
    /// Also the device force fit ([`Identification::device`]) and the identified model
    /// simulated against every test ([`Identification::comparison`]): the `identify`
    /// command and its report.
    Complete,
}

/// Identify everything the campaign allows (paper section 4), in dependency order, after
/// screening every record ([`crate::campaign::screen`]), with the device fit and the
/// comparison ([`Scope::Complete`]).
pub fn identify(c: &Campaign) -> Identification {
    identify_screened_with(&screen(c), Scope::Complete)
}

/// The parameters ([`Scope::Parameters`]) of an already screened campaign: what the
/// diagnosis builds its baseline on.
pub fn identify_screened(s: &Screening) -> Identification {
    identify_screened_with(s, Scope::Parameters)
}

impl Identification {
    /// The parts of the model section 4 could not identify (each would otherwise be a
    /// default, which a diagnosis must not extend).
    pub fn section4_gaps(&self) -> Vec<&'static str> {
        [
            (self.servovalve.is_none(), "servovalve"),
            (self.mass_kg.is_none(), "mass"),
            (self.friction.is_none(), "Bouc-Wen friction"),
            (self.oil_column.is_none(), "oil column"),
        ]
        .into_iter()
        .filter_map(|(absent, name)| absent.then_some(name))
        .collect()
    }

    /// The JSON of issue 5 (nested objects, fixed keys) with an `uncertainty` object.
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::{json, Map, Value};
        let v = self.servovalve.as_ref();
        let val = self.validation.as_ref();
        let p = &self.params;
        let mut out = json!({
            "servovalve": { "model": v.map(|v| v.chosen.name()).unwrap_or("unidentified") },
            "validation": { "test": val.map(|v| v.test.clone()) },
            "actuator": { "model": p.actuator.model.name() },
            "read": self.read,
            "missing": self.missing,
            "screening": self.screening,
            "defaults": self.defaults().into_iter().map(|(k, r)| json!({"key": k, "reason": r})).collect::<Vec<_>>(),
            "warnings": self.warnings(),
        });
        let mut unc = Map::new();
        for e in self.estimates() {
            let (block, key) = e.key().split_once('.').unwrap_or(("", e.key()));
            out[block][key] = e
                .value
                .filter(|x| x.is_finite())
                .map_or(Value::Null, |x| json!(x));
            if let Some(s) = e.sigma.filter(|s| s.is_finite()) {
                let entry = unc.entry(block.to_string()).or_insert_with(|| json!({}));
                entry[key] = json!(s);
            }
        }
        out["uncertainty"] = Value::Object(unc);
        // the table carrying modes that the mass rests on, null for a rigid one
        let carried = self.mass_random.as_ref().and_then(|m| m.carried.as_ref());
        out["table"]["carried"] = serde_json::to_value(carried).unwrap_or(Value::Null);
        if let Some(d) = &self.device {
            out["device"]["test"] = json!(d.test);
            out["device"]["checked_on"] = d
                .validation
                .iter()
                .map(|t| json!({"test": t.test, "nrmse": t.nrmse, "fit_percent": t.fit_percent}))
                .collect();
        }
        out["closed_loop"] = serde_json::to_value(&self.closed_loop).unwrap_or(Value::Null);
        out["comparison"] = serde_json::to_value(&self.comparison).unwrap_or(Value::Null);
        out
    }

    /// What the estimates should not be taken for: an apparent mass that is not a rigid
    /// body's ([`MassFit::not_rigid`]).
    pub fn warnings(&self) -> Vec<String> {
        self.mass_random
            .iter()
            .filter_map(|m| m.not_rigid())
            .collect()
    }

    /// The parameter-file keys that hold a default, not an identified value, and why (the
    /// operating envelope always: no recording gives it).
    pub fn defaults(&self) -> Vec<(&'static str, &'static str)> {
        let mut d: Vec<(&'static str, &'static str)> = self
            .unknown_inputs
            .iter()
            .map(|k| (*k, UNKNOWN_INPUT))
            .collect();
        d.extend(self.unidentified_keys());
        if let Some(cl) = &self.closed_loop {
            let fitted = |k: &str| cl.estimates.iter().any(|e| e.key == k);
            let held = |k: &str| cl.conventions.iter().any(|e| e.key == k);
            d.retain(|(k, _)| !fitted(k) && !held(k));
            d.extend(cl.conventions.iter().map(|c| (c.key, c.reason)));
        }
        for (k, why) in d.iter_mut() {
            if unused_by_valve(self.params.servovalve.model, k) {
                *why = UNUSED_BY_VALVE;
            }
        }
        d.extend(LIMIT_KEYS.iter().map(|k| (*k, LIMITS_DEFAULT)));
        d
    }

    /// The keys of each section-4 estimate that could not be made, with why.
    fn unidentified_keys(&self) -> Vec<(&'static str, &'static str)> {
        let groups: [(bool, &[&'static str], &'static str); 5] = [
            (
                self.servovalve.is_none(),
                &[
                    "servovalve.gain",
                    "servovalve.time_constant_s",
                    "servovalve.natural_frequency_hz",
                    "servovalve.damping_ratio",
                ],
                "servovalve not identified (see missing)",
            ),
            (
                self.mass_kg.is_none(),
                &["table.mass_kg"],
                "no mass estimate (see missing)",
            ),
            (
                self.triangles.is_none(),
                &["table.stiffness_n_m"],
                "no triangle estimate: zero stiffness assumed",
            ),
            (
                self.friction.is_none(),
                &[
                    "friction.force_n",
                    "friction.yield_displacement_m",
                    "friction.shape",
                ],
                "Bouc-Wen friction not identified (see missing)",
            ),
            (
                self.oil_column.is_none(),
                &["actuator.bulk_modulus_pa", "actuator.leakage_m3_s_pa"],
                "oil column not identified (see missing)",
            ),
        ];
        groups
            .into_iter()
            .filter(|(missing, ..)| *missing)
            .flat_map(|(_, keys, why)| keys.iter().map(move |k| (*k, why)))
            .collect()
    }

    /// Oil-column figures of the identified parameters.
    pub fn oil_column_of_params(&self) -> OilColumn {
        OilColumn::of(&self.params)
    }
}

/// The operating envelope's keys (spec section 8): campaign.toml has no key for them and
/// no recording shows them, so the parameter file always holds the TREES Lab table's.
const LIMIT_KEYS: [&str; 2] = ["limits.stroke_m", "limits.velocity_m_s"];

/// Why a geometry or gain key the campaign does not give holds a default.
const UNKNOWN_INPUT: &str = "not in campaign.toml and not identified from these recordings: \
     TREES Lab default written, not a property of this table";

/// Why a key of the other valve order holds a default ([`unused_by_valve`]).
const UNUSED_BY_VALVE: &str = "not used by the chosen valve order (servovalve.model): written \
     for a switch of order, not a property of this table";

/// Why [`LIMIT_KEYS`] are defaults.
const LIMITS_DEFAULT: &str = "no recording shows the operating envelope: the TREES Lab \
     table's stroke and velocity written; set this table's own before simulating near them";

/// Whether servovalve key `key` is unused by a valve of order `model`.
fn unused_by_valve(model: crate::params::ServovalveModel, key: &str) -> bool {
    use crate::params::ServovalveModel::*;
    match model {
        SecondOrder => key == "servovalve.time_constant_s",
        FirstOrder | Delay => {
            key == "servovalve.natural_frequency_hz" || key == "servovalve.damping_ratio"
        }
    }
}

/// A short campaign of the simulator's TREES Lab table for the estimators' unit tests:
/// the named tests of the paper's program (seed 1), with 12 s of random.
#[cfg(test)]
pub(crate) fn short_test_campaign(tests: &[&str]) -> Campaign {
    use crate::campaign::synth::{synthesise, SynthOptions};
    let opts = SynthOptions {
        random_duration_s: 12.0,
        tests: Some(tests.iter().map(|t| t.to_string()).collect()),
        ..SynthOptions::default()
    };
    synthesise(&crate::params::Params::trees_lab(), &opts, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The diagnosis's identification ([`Scope::Parameters`]) identifies the same model as
    /// the complete one and leaves out the device fit, which only the latter attempts.
    #[test]
    fn the_parameters_scope_identifies_the_same_model_without_the_device() {
        let screened = screen(&short_test_campaign(&["R2"]));
        let complete = identify_screened_with(&screened, Scope::Complete);
        let parameters = identify_screened(&screened);
        assert_eq!(parameters.params, complete.params);
        assert!(parameters.device.is_none());
        let device_noted = |id: &Identification| id.missing.iter().any(|m| m.contains("device"));
        assert!(complete.device.is_some() || device_noted(&complete));
        assert!(!device_noted(&parameters), "{:?}", parameters.missing);
    }
}
