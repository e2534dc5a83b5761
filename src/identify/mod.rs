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

mod device;
mod error;
mod estimates;
pub mod frf;
mod friction;
pub mod greybox;
pub mod lsq;
mod mass;
mod oil_column;
mod periodic;
mod results;
pub mod select;
mod servovalve;
pub(crate) mod signals;
pub mod spool;
mod validation;

pub use device::fit_device;
pub use error::IdentifyError;
pub use estimates::Estimate;
pub use friction::{bouc_wen_path, fit_friction, fit_triangles};
pub use mass::{fit_mass, fit_mass_corrected};
pub use oil_column::{fit_oil_column, OilColumnInput, OilGeometry};
pub use periodic::{fit_friction_and_mass, fit_mass_periodic};
pub use results::*;
pub use servovalve::{fit_servovalve, relative_error};
pub use validation::validate;

use crate::campaign::screen::{screen, Action, Screening};
use crate::campaign::{Campaign, Record};
use crate::linear::{OilColumn, ValveTf};
use crate::params::{ActuatorModel, Params};
use frf::WelchOptions;

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

/// Why no test can take a role (`role` says which and what it needs): none of that
/// kind, or the screening excluded them (named with the reasons).
fn absent_role(s: &Screening, role: &str, what: &str) -> IdentifyError {
    IdentifyError::NoTest {
        role: role.to_string(),
        excluded: s
            .findings
            .iter()
            .filter(|f| f.action == Action::TestExcluded)
            .map(|f| f.to_string())
            .collect(),
        consequence: what.to_string(),
    }
}

/// `r` with the file of test `name` added to its error.
fn in_file<T>(c: &Campaign, name: &str, r: Result<T, IdentifyError>) -> Result<T, IdentifyError> {
    let file = c
        .test(name)
        .map(|(s, _)| s.file.clone())
        .unwrap_or_default();
    r.map_err(|e| IdentifyError::InFile {
        error: Box::new(e),
        file,
    })
}

/// The parameters ([`Scope::Parameters`]) of an already screened campaign: what the
/// diagnosis builds its baseline on.
pub fn identify_screened(s: &Screening) -> Identification {
    identify_screened_with(s, Scope::Parameters)
}

/// [`identify`] on an already screened campaign, computing what `scope` asks for.
pub fn identify_screened_with(s: &Screening, scope: Scope) -> Identification {
    let c = &s.campaign;
    // each test at its own rate (campaign-format.md, "campaign.toml additions")
    let fs = |i: usize| c.sample_rate_of(i);
    let g = &c.info.geometry;
    let mut missing = Vec::new();
    let mut note = |r: Result<(), IdentifyError>| {
        if let Err(e) = r {
            missing.push(e.to_string());
        }
    };
    // start from the defaults with the lab's geometry and controller; `defaults` lists
    // what stays a default and why
    let mut p = Params::trees_lab();
    let unknown_inputs = c.info.apply_known(&mut p);

    let roles = select::random_roles(c);
    let name = |i: usize| c.info.tests[i].name.as_str();
    let valve = match roles.valve {
        Some(i) => in_file(c, name(i), fit_servovalve(name(i), &c.records[i], fs(i))),
        None => Err(absent_role(
            s,
            "valve test (a random test recording the valve command and the spool)",
            "servovalve not identified by section 4 (see defaults for what the parameter file holds)",
        )),
    };
    let valve = valve.map_err(|e| note(Err(e))).ok();
    if let Some(v) = &valve {
        p.servovalve.model = v.chosen;
        p.servovalve.gain = v.gain;
        p.servovalve.time_constant_s = v.time_constant_s;
        p.servovalve.natural_frequency_hz = v.natural_frequency_hz;
        p.servovalve.damping_ratio = v.damping_ratio;
    }
    let mass_random = match roles.mass {
        Some(i) => in_file(c, name(i), fit_mass(name(i), &c.records[i], fs(i))),
        None => Err(absent_role(
            s,
            "mass test (a random test besides the valve test)",
            "mass not identified from random data",
        )),
    };
    let mass_random = mass_random.map_err(|e| note(Err(e))).ok();
    let m0 = mass_random.as_ref().map(|m| m.mass_kg);
    let triangles = fit_triangles(c, m0.unwrap_or(p.table.mass_kg))
        .map_err(|e| note(Err(e)))
        .ok();
    let k = triangles.as_ref().map(|t| t.stiffness_n_m).unwrap_or(0.0);
    let f_mu0 = triangles
        .as_ref()
        .map(|t| t.sliding_friction_n)
        .unwrap_or(p.friction.force_n);
    let (slow_sines, fast_sines) = select::sine_roles(c, m0.unwrap_or(p.table.mass_kg), f_mu0);
    let (friction, mass_periodic) = match m0 {
        Some(m0) => {
            let fr = fit_friction(c, &slow_sines, m0, k, f_mu0).map_err(|e| note(Err(e)));
            let mp = fit_mass_periodic(c, &fast_sines, k, fr.as_ref().ok());
            (fr.ok(), mp.map_err(|e| note(Err(e))).ok())
        }
        // no random test's mass: friction and mass from the sines together
        None => {
            let (fr, mp) = periodic::periodic_without_random_mass(c, k, f_mu0);
            (
                fr.map_err(|e| note(Err(e))).ok(),
                mp.map_err(|e| note(Err(e))).ok(),
            )
        }
    };
    // refine the random-data mass with the friction removed in the time domain
    let mass_random = match (&mass_random, &friction, roles.mass) {
        (Some(_), Some(fr), Some(i)) => {
            fit_mass_corrected(name(i), &c.records[i], fs(i), Some((fr, k)))
                .ok()
                .or(mass_random)
        }
        _ => mass_random,
    };
    let mass_kg = final_mass(mass_random.as_ref(), mass_periodic.as_ref());
    if mass_kg.is_none() {
        note(Err(IdentifyError::not_usable(
            "no mass estimate: table.mass_kg is not identified by section 4 (see defaults for what the parameter file holds)",
        )));
    }
    p.table.mass_kg = mass_kg.unwrap_or(p.table.mass_kg);
    // triangles fitted with the default mass (no random test): again with the identified
    let triangles = match (m0, mass_kg) {
        (None, Some(m)) if triangles.is_some() => fit_triangles(c, m).ok().or(triangles),
        _ => triangles,
    };
    let k = triangles.as_ref().map_or(k, |t| t.stiffness_n_m);
    p.table.stiffness_n_m = k.max(0.0);
    if let Some(fr) = &friction {
        p.friction.force_n = fr.force_n;
        p.friction.yield_displacement_m = fr.yield_displacement_m;
        p.friction.shape = fr.shape.min(0.999);
    }
    // the identified servovalve carries the valve command to the spool in the oil-column fit
    let valve_tf = valve.as_ref().map(|_| ValveTf::new(&p));
    let oil = match (roles.oil_column, mass_kg) {
        (Some(i), Some(m)) => OilGeometry::from_campaign(g).and_then(|og| {
            in_file(
                c,
                name(i),
                fit_oil_column(name(i), &c.records[i], fs(i), &og, m, valve_tf.as_ref()),
            )
        }),
        (Some(_), None) => Err(IdentifyError::NeedsUpstream {
            what: "oil column".into(),
            needs: "the identified mass".into(),
        }),
        (None, _) => Err(absent_role(
            s,
            "oil-column test (a third random test, with the spool)",
            "oil column not identified",
        )),
    };
    let oil = oil.map_err(|e| note(Err(e))).ok();
    if let Some(o) = &oil {
        p.actuator.bulk_modulus_pa = o.bulk_modulus_pa;
        p.actuator.leakage_m3_s_pa = o.leakage_m3_s_pa;
    }
    let validation = match roles.validation() {
        Some(i) => in_file(c, name(i), validate(c, name(i), &p)),
        None => Err(IdentifyError::not_usable(
            "no random test usable: validation skipped",
        )),
    };
    let validation = validation.map_err(|e| note(Err(e))).ok();
    if let Some(v) = &validation {
        if v.table_tf_error_nonlinear < v.table_tf_error {
            p.actuator.model = ActuatorModel::Nonlinear;
        }
    }
    let device = match scope {
        Scope::Complete => device_fit(s).map_err(|e| note(Err(e))).ok(),
        Scope::Parameters => None,
    };
    let known = greybox::Known {
        servovalve: valve.is_some(),
        mass: mass_kg.is_some(),
        oil_column: oil.is_some(),
        friction: friction.is_some(),
    };
    // the model is compared with the campaign without the set-aside displacements
    let compared = s.compared();
    let closed_loop = closed_loop(compared, &p, known, &unknown_inputs)
        .and_then(|r| r.map_err(|e| note(Err(e))).ok());
    if let Some(cl) = &closed_loop {
        p = cl.params;
    }
    let comparison = match (&closed_loop, scope) {
        (Some(cl), _) => cl.fits.clone(),
        (None, Scope::Complete) => compare_all(compared, &p),
        (None, Scope::Parameters) => Vec::new(),
    };
    // the segments of the random tests' spectra, at the rate of the first one used (a
    // test at another rate keeps the resolution, with segments of its own length)
    let first_random = roles.valve.or(roles.mass).or(roles.oil_column);
    let welch_rate = first_random.map_or(c.info.sample_rate_hz, fs);
    let welch = WelchOptions::for_resolution(welch_rate, RESOLUTION_HZ);
    Identification {
        campaign: c.info.name.clone(),
        read: s.read.clone(),
        servovalve: valve,
        triangles,
        mass_random,
        friction,
        mass_periodic,
        oil_column: oil,
        validation,
        device,
        mass_kg,
        params: p,
        missing,
        screening: s.findings.clone(),
        welch,
        unknown_inputs,
        closed_loop,
        comparison,
    }
}

/// The device force between actuator and reaction ([`device`]) from the first test
/// recording displacement and force, or why there is none.
fn device_fit(s: &Screening) -> Result<DeviceFit, IdentifyError> {
    let c = &s.campaign;
    match select::device_roles(c) {
        Some(r) => in_file(c, &c.info.tests[r.fit].name, fit_device(c, &r)),
        None => Err(absent_role(
            s,
            "device test (a test recording displacement_m and force_n)",
            "device force not identified",
        )),
    }
}

/// Tests that can take part in a closed-loop fit: a measured displacement or acceleration.
fn motion_tests(c: &Campaign) -> Vec<usize> {
    (0..c.records.len())
        .filter(|&i| {
            let r = &c.records[i];
            r.displacement_m.is_some() || r.acceleration_m_s2.is_some()
        })
        .collect()
}

/// The grey-box fit of the closed loop when something the simulation needs is neither
/// given nor identified (`None` when the section-4 chain gave everything); a free valve's
/// order is the data's, for the `identify` command and the diagnosis alike.
fn closed_loop(
    c: &Campaign,
    p: &Params,
    known: greybox::Known,
    unknown_inputs: &[&'static str],
) -> Option<Result<greybox::ClosedLoopFit, IdentifyError>> {
    let complete = known.servovalve && known.mass && known.oil_column && known.friction;
    let gains_known = !unknown_inputs.iter().any(|k| k.starts_with("controller."));
    if complete && gains_known {
        return None;
    }
    Some(greybox::fit_closed_loop(c, &motion_tests(c), p, known))
}

/// The identified model against every test with a measured motion (the section-4
/// estimators chose their tests; these figures are the whole campaign's, marked as
/// estimation data).
fn compare_all(c: &Campaign, p: &Params) -> Vec<greybox::ChannelFit> {
    if c.gains_known().is_err() {
        return Vec::new();
    }
    let tests: Vec<(usize, greybox::Role)> = motion_tests(c)
        .into_iter()
        .map(|i| (i, greybox::Role::Estimation))
        .collect();
    greybox::compare::compare(p, c, &tests, &greybox::compare::COMPARED).fits
}

/// The final mass: inverse-variance mean of the random and periodic estimates, `None`
/// when neither exists.
fn final_mass(random: Option<&MassFit>, periodic: Option<&PeriodicMassFit>) -> Option<f64> {
    let mut num = 0.0;
    let mut den = 0.0;
    for (m, s) in [
        random.map(|m| (m.mass_kg, m.sigma_mass_kg)),
        periodic.map(|m| (m.mass_kg, m.sigma_mass_kg)),
    ]
    .into_iter()
    .flatten()
    {
        let s = if s.is_finite() { s } else { m.abs() };
        let w = 1.0 / s.max(1e-3 * m.abs()).powi(2);
        num += w * m;
        den += w;
    }
    Some(num / den).filter(|m| den > 0.0 && m.is_finite())
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
        });
        let mut unc = Map::new();
        for e in self.estimates() {
            let (block, key) = e.key.split_once('.').unwrap_or(("", e.key));
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

    /// The parameter-file keys that hold a default, not an identified value, and why (the
    /// operating envelope always: no recording gives it).
    pub fn defaults(&self) -> Vec<(&'static str, &'static str)> {
        let mut d: Vec<(&'static str, &'static str)> = self
            .unknown_inputs
            .iter()
            .map(|k| {
                (
                    *k,
                    "not in campaign.toml and not identified from these recordings: \
                     TREES Lab default written, not a property of this table",
                )
            })
            .collect();
        let mut add = |missing: bool, keys: &[&'static str], why: &'static str| {
            if missing {
                d.extend(keys.iter().map(|k| (*k, why)));
            }
        };
        add(
            self.servovalve.is_none(),
            &[
                "servovalve.gain",
                "servovalve.time_constant_s",
                "servovalve.natural_frequency_hz",
                "servovalve.damping_ratio",
            ],
            "servovalve not identified (see missing)",
        );
        add(
            self.mass_kg.is_none(),
            &["table.mass_kg"],
            "no mass estimate (see missing)",
        );
        add(
            self.triangles.is_none(),
            &["table.stiffness_n_m"],
            "no triangle estimate: zero stiffness assumed",
        );
        add(
            self.friction.is_none(),
            &[
                "friction.force_n",
                "friction.yield_displacement_m",
                "friction.shape",
            ],
            "Bouc-Wen friction not identified (see missing)",
        );
        add(
            self.oil_column.is_none(),
            &["actuator.bulk_modulus_pa", "actuator.leakage_m3_s_pa"],
            "oil column not identified (see missing)",
        );
        if let Some(cl) = &self.closed_loop {
            let fitted = |k: &str| cl.estimates.iter().any(|e| e.key == k);
            let held = |k: &str| cl.conventions.iter().any(|e| e.key == k);
            d.retain(|(k, _)| !fitted(k) && !held(k));
            d.extend(cl.conventions.iter().map(|c| (c.key, c.reason)));
        }
        for (k, why) in d.iter_mut() {
            if unused_by_valve(self.params.servovalve.model, k) {
                *why = "not used by the chosen valve order (servovalve.model): written for a \
                        switch of order, not a property of this table";
            }
        }
        d.extend(LIMIT_KEYS.iter().map(|k| (*k, LIMITS_DEFAULT)));
        d
    }

    /// Oil-column figures of the identified parameters.
    pub fn oil_column_of_params(&self) -> OilColumn {
        OilColumn::of(&self.params)
    }
}

/// The operating envelope's keys (spec section 8): campaign.toml has no key for them and
/// no recording shows them, so the parameter file always holds the TREES Lab table's.
const LIMIT_KEYS: [&str; 2] = ["limits.stroke_m", "limits.velocity_m_s"];

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::{synthesise, SynthOptions};

    /// The diagnosis's identification ([`Scope::Parameters`]) identifies the same model as
    /// the complete one and leaves out the device fit, which only the latter attempts.
    #[test]
    fn the_parameters_scope_identifies_the_same_model_without_the_device() {
        let opts = SynthOptions {
            random_duration_s: 12.0,
            tests: Some(vec!["R2".into()]),
            ..SynthOptions::default()
        };
        let screened = screen(&synthesise(&Params::trees_lab(), &opts, None));
        let complete = identify_screened_with(&screened, Scope::Complete);
        let parameters = identify_screened(&screened);
        assert_eq!(parameters.params, complete.params);
        assert!(parameters.device.is_none());
        let device_noted = |id: &Identification| id.missing.iter().any(|m| m.contains("device"));
        assert!(complete.device.is_some() || device_noted(&complete));
        assert!(!device_noted(&parameters), "{:?}", parameters.missing);
    }
}
