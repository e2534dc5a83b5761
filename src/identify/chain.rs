//! The section-4 chain (module doc of [`super`]): each estimator in dependency order, each
//! writing what it identified into the parameters and noting what it could not
//! ([`Missing`]), then the closed-loop fit of what stays unknown.

use super::frf::WelchOptions;
use super::missing::{Estimation, Missing};
use super::{
    fit_device, fit_friction, fit_mass, fit_mass_corrected, fit_mass_periodic, fit_oil_column,
    fit_servovalve, fit_triangles, greybox, periodic, select, validate, ColumnMass, DeviceFit,
    FrictionFit, Identification, IdentifyError, MassFit, OilColumnFit, OilGeometry,
    PeriodicMassFit, Scope, ServovalveFit, TriangleFit, Validation, RESOLUTION_HZ,
};
use crate::campaign::screen::{Action, Screening};
use crate::campaign::{Campaign, Record};
use crate::linear::ValveTf;
use crate::params::{ActuatorModel, Params};

/// [`super::identify`] on an already screened campaign, computing what `scope` asks for.
pub fn identify_screened_with(s: &Screening, scope: Scope) -> Identification {
    let mut chain = Chain::new(s);
    let servovalve = chain.servovalve();
    let mechanics = chain.mechanics();
    let column_mass = mechanics.mass_kg.map(|mass_kg| ColumnMass {
        mass_kg,
        carried: (mechanics.mass_random.as_ref()).and_then(|m| m.carried.clone()),
    });
    let oil_column = chain.oil_column(servovalve.is_some(), column_mass);
    let validation = chain.validation();
    let device = match scope {
        Scope::Complete => chain.keep(Estimation::Device, device_fit(s)),
        Scope::Parameters => None,
    };
    let known = greybox::Known {
        servovalve: servovalve.is_some(),
        mass: mechanics.mass_kg.is_some(),
        oil_column: oil_column.is_some(),
        friction: mechanics.friction.is_some(),
    };
    let closed_loop = chain.closed_loop(known);
    let comparison = match (&closed_loop, scope) {
        (Some(cl), _) => cl.fits.clone(),
        (None, Scope::Complete) => compare_all(s.compared(), &chain.p),
        (None, Scope::Parameters) => Vec::new(),
    };
    Identification {
        campaign: chain.c.info.name.clone(),
        read: s.read.clone(),
        servovalve,
        triangles: mechanics.triangles,
        mass_random: mechanics.mass_random,
        friction: mechanics.friction,
        mass_periodic: mechanics.mass_periodic,
        oil_column,
        validation,
        device,
        mass_kg: mechanics.mass_kg,
        params: chain.p,
        screening: s.findings.clone(),
        welch: chain.welch(),
        missing: chain.missing,
        unknown_inputs: chain.unknown_inputs,
        closed_loop,
        comparison,
    }
}

/// The chain under way: the campaign, the roles of its random tests, the parameters
/// identified so far and what could not be.
struct Chain<'a> {
    s: &'a Screening,
    c: &'a Campaign,
    roles: select::RandomRoles,
    /// The defaults with the lab's geometry and controller; each step writes what it
    /// identified ([`Identification::defaults`] lists what stays a default and why).
    p: Params,
    unknown_inputs: Vec<&'static str>,
    missing: Vec<Missing>,
}

/// The estimates of the table's mechanics: mass, stiffness and friction (4.1.2, 4.2).
struct Mechanics {
    mass_random: Option<MassFit>,
    triangles: Option<TriangleFit>,
    friction: Option<FrictionFit>,
    mass_periodic: Option<PeriodicMassFit>,
    /// The final mass ([`final_mass`]).
    mass_kg: Option<f64>,
}

/// The name of test `i` of `c`.
fn test_name(c: &Campaign, i: usize) -> &str {
    c.info.tests[i].name.as_str()
}

impl<'a> Chain<'a> {
    fn new(s: &'a Screening) -> Chain<'a> {
        let c = &s.campaign;
        let mut p = Params::trees_lab();
        let unknown_inputs = c.info.apply_known(&mut p);
        Chain {
            s,
            c,
            roles: select::random_roles(c),
            p,
            unknown_inputs,
            missing: Vec::new(),
        }
    }

    /// The value of `r`, or `None` with its error noted as why `estimation` is missing.
    fn keep<T>(&mut self, estimation: Estimation, r: Result<T, IdentifyError>) -> Option<T> {
        match r {
            Ok(x) => Some(x),
            Err(e) => {
                self.missing.push(Missing::new(estimation, e));
                None
            }
        }
    }

    /// `estimation` missing for `reason`.
    fn note(&mut self, estimation: Estimation, reason: IdentifyError) {
        self.missing.push(Missing::new(estimation, reason));
    }

    /// The servovalve from the valve test (4.1.1), written into the parameters.
    fn servovalve(&mut self) -> Option<ServovalveFit> {
        let c = self.c;
        let fit = match self.roles.valve {
            Some(i) => fit_on_test(c, i, fit_servovalve),
            None => Err(absent_role(
                self.s,
                "valve test (a random test recording the valve command and the spool)",
                "servovalve not identified by section 4 (see defaults for what the parameter file holds)",
            )),
        };
        let v = self.keep(Estimation::Servovalve, fit)?;
        let sv = &mut self.p.servovalve;
        sv.model = v.chosen;
        sv.gain = v.gain;
        sv.time_constant_s = v.time_constant_s;
        sv.natural_frequency_hz = v.natural_frequency_hz;
        sv.damping_ratio = v.damping_ratio;
        Some(v)
    }

    /// Mass, stiffness and friction (4.1.2, 4.2.1-4.2.3), written into the parameters:
    /// the random test's mass, the triangles with it, the sines with both, the random
    /// mass refined with the friction, and the triangles again with the final mass when
    /// they had the default.
    fn mechanics(&mut self) -> Mechanics {
        let mass_random = self.mass_random();
        let m0 = mass_random.as_ref().map(|m| m.mass_kg);
        let triangles = self.keep(
            Estimation::Triangles,
            fit_triangles(self.c, m0.unwrap_or(self.p.table.mass_kg)),
        );
        let k = triangles.as_ref().map(|t| t.stiffness_n_m).unwrap_or(0.0);
        let f_mu0 = triangles
            .as_ref()
            .map(|t| t.sliding_friction_n)
            .unwrap_or(self.p.friction.force_n);
        let (friction, mass_periodic) = self.sines(m0, k, f_mu0);
        let mass_random = self.refined_mass(mass_random, friction.as_ref(), k);
        let mass_kg = final_mass(mass_random.as_ref(), mass_periodic.as_ref());
        if mass_kg.is_none() {
            self.note(Estimation::Mass, IdentifyError::not_usable(
                "no mass estimate: table.mass_kg is not identified by section 4 (see defaults for what the parameter file holds)",
            ));
        }
        self.p.table.mass_kg = mass_kg.unwrap_or(self.p.table.mass_kg);
        // triangles fitted with the default mass (no random test): again with the identified
        let triangles = match (m0, mass_kg) {
            (None, Some(m)) if triangles.is_some() => fit_triangles(self.c, m).ok().or(triangles),
            _ => triangles,
        };
        let k = triangles.as_ref().map_or(k, |t| t.stiffness_n_m);
        self.p.table.stiffness_n_m = k.max(0.0);
        if let Some(fr) = &friction {
            self.p.friction.force_n = fr.force_n;
            self.p.friction.yield_displacement_m = fr.yield_displacement_m;
            self.p.friction.shape = fr.shape.min(0.999);
        }
        Mechanics {
            mass_random,
            triangles,
            friction,
            mass_periodic,
            mass_kg,
        }
    }

    /// The apparent mass of the mass test (4.1.2).
    fn mass_random(&mut self) -> Option<MassFit> {
        let c = self.c;
        let fit = match self.roles.mass {
            Some(i) => fit_on_test(c, i, fit_mass),
            None => Err(absent_role(
                self.s,
                "mass test (a random test besides the valve test)",
                "mass not identified from random data",
            )),
        };
        self.keep(Estimation::MassRandom, fit)
    }

    /// Bouc-Wen friction from the slow sines and the loop mass from the fast ones, with
    /// the random test's mass `m0` (4.2.2-4.2.3); without it, both from the sines together
    /// ([`periodic`]). `k` and `f_mu0`: the triangles' stiffness and sliding friction.
    fn sines(
        &mut self,
        m0: Option<f64>,
        k: f64,
        f_mu0: f64,
    ) -> (Option<FrictionFit>, Option<PeriodicMassFit>) {
        let c = self.c;
        let (slow_sines, fast_sines) =
            select::sine_roles(c, m0.unwrap_or(self.p.table.mass_kg), f_mu0);
        match m0 {
            Some(m0) => {
                let fr = self.keep(
                    Estimation::Friction,
                    fit_friction(c, &slow_sines, m0, k, f_mu0),
                );
                let mp = fit_mass_periodic(c, &fast_sines, k, fr.as_ref());
                (fr, self.keep(Estimation::MassPeriodic, mp))
            }
            None => {
                let (fr, mp) = periodic::periodic_without_random_mass(c, k, f_mu0);
                let fr = self.keep(Estimation::Friction, fr);
                (fr, self.keep(Estimation::MassPeriodic, mp))
            }
        }
    }

    /// The random test's mass again with the friction removed in the time domain (eqs.
    /// 4.14-4.15 along the measured path), else as it was.
    fn refined_mass(
        &self,
        mass_random: Option<MassFit>,
        friction: Option<&FrictionFit>,
        k: f64,
    ) -> Option<MassFit> {
        let c = self.c;
        match (&mass_random, friction, self.roles.mass) {
            (Some(_), Some(fr), Some(i)) => {
                let name = test_name(c, i);
                fit_mass_corrected(name, &c.records[i], c.sample_rate_of(i), Some((fr, k)))
                    .ok()
                    .or(mass_random)
            }
            _ => mass_random,
        }
    }

    /// The oil column (4.1.3) behind the identified `mass`, the identified
    /// servovalve (when `with_valve`) carrying the valve command to the spool; written
    /// into the parameters.
    fn oil_column(&mut self, with_valve: bool, mass: Option<ColumnMass>) -> Option<OilColumnFit> {
        let c = self.c;
        let valve_tf = with_valve.then(|| ValveTf::new(&self.p));
        let fit = match (self.roles.oil_column, mass) {
            (Some(i), Some(m)) => OilGeometry::from_campaign(&c.info.geometry).and_then(|og| {
                let name = test_name(c, i);
                let fs = c.sample_rate_of(i);
                let fit = fit_oil_column(name, &c.records[i], fs, &og, m, valve_tf.as_ref());
                in_file(c, name, fit)
            }),
            (Some(_), None) => Err(IdentifyError::NeedsUpstream {
                what: "oil column".into(),
                needs: "the identified mass".into(),
            }),
            (None, _) => Err(absent_role(
                self.s,
                "oil-column test (a third random test, with the spool)",
                "oil column not identified",
            )),
        };
        let o = self.keep(Estimation::OilColumn, fit)?;
        self.p.actuator.bulk_modulus_pa = o.bulk_modulus_pa;
        self.p.actuator.leakage_m3_s_pa = o.leakage_m3_s_pa;
        Some(o)
    }

    /// The table TF of the identified model against the validation test (section 5); the
    /// nonlinear actuator chosen when it fits better.
    fn validation(&mut self) -> Option<Validation> {
        let c = self.c;
        let v = match self.roles.validation() {
            Some(i) => in_file(c, test_name(c, i), validate(c, test_name(c, i), &self.p)),
            None => Err(IdentifyError::not_usable(
                "no random test usable: validation skipped",
            )),
        };
        let v = self.keep(Estimation::Validation, v)?;
        if v.table_tf_error_nonlinear < v.table_tf_error {
            self.p.actuator.model = ActuatorModel::Nonlinear;
        }
        Some(v)
    }

    /// The closed-loop fit when section 4 left something unknown ([`closed_loop`]), on
    /// the campaign without the set-aside displacements; its parameters replace the chain's.
    fn closed_loop(&mut self, known: greybox::Known) -> Option<greybox::ClosedLoopFit> {
        let fit = closed_loop(self.s.compared(), &self.p, known, &self.unknown_inputs)?;
        let cl = self.keep(Estimation::ClosedLoop, fit)?;
        self.p = cl.params;
        Some(cl)
    }

    /// The segments of the random tests' spectra, at the rate of the first one used (a
    /// test at another rate keeps the resolution, with segments of its own length).
    fn welch(&self) -> WelchOptions {
        let r = &self.roles;
        let first_random = r.valve.or(r.mass).or(r.oil_column);
        let rate = first_random.map_or(self.c.info.sample_rate_hz, |i| self.c.sample_rate_of(i));
        WelchOptions::for_resolution(rate, RESOLUTION_HZ)
    }
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

/// The estimator `fit` on test `i` (its name, record and sample rate), its error naming
/// the test's file.
fn fit_on_test<T>(
    c: &Campaign,
    i: usize,
    fit: fn(&str, &Record, f64) -> Result<T, IdentifyError>,
) -> Result<T, IdentifyError> {
    let name = test_name(c, i);
    in_file(c, name, fit(name, &c.records[i], c.sample_rate_of(i)))
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

/// The device force between actuator and reaction ([`super::device`]) from the first
/// test recording displacement and force, or why there is none.
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
