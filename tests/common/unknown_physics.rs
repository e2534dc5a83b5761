#![allow(dead_code)]
//! Physics no catalogue row of `model.md` section 7 describes (issue 17's open world), put
//! on a synthetic campaign: the paper's program synthesised as `campaign synth` does (same
//! references and seeded noise), then each test simulated again sample by sample with a
//! body's force on the table through the model's external-force input (held over a sample,
//! as a co-simulation master does), its recordings replaced. With no force the campaign is
//! the one `campaign synth` writes, bit for bit. Used by `tests/diagnose_unknown.rs` and
//! `examples/unknown_physics.rs`.

use shaketable::campaign::synth::{
    reference, selected_program, synthesise_program, synthesise_test, write_synthetic,
    SynthOptions, SynthTest,
};
use shaketable::campaign::Record;
use shaketable::model::{Inputs, Model, Outputs, SensorNoise};
use shaketable::params::Params;
use shaketable::solver::Simulator;
use std::path::Path;

/// A body the table drives: its force on the table from the table's displacement and
/// velocity at the start of a sample, then its own state advanced over the sample.
pub trait Body {
    fn force_n(&self, x_m: f64, v_m_s: f64) -> f64;
    fn advance(&mut self, _x_m: f64, _v_m_s: f64, _dt_s: f64) {}
}

/// Drag `-c v|v|`; `c` gives 5 kN at 0.3 m/s, about the friction's amplitude.
struct QuadraticDamping {
    c_n_s2_m2: f64,
}

impl Body for QuadraticDamping {
    fn force_n(&self, _x: f64, v: f64) -> f64 {
        -self.c_n_s2_m2 * v * v.abs()
    }
}

/// Hardening spring `-k x^3`; `k` gives 10 kN at 50 mm.
struct CubicSpring {
    k_n_m3: f64,
}

impl Body for CubicSpring {
    fn force_n(&self, x: f64, _v: f64) -> f64 {
        -self.k_n_m3 * x.powi(3)
    }
}

/// A single-degree-of-freedom specimen whose spring is elastic-perfectly-plastic, with
/// viscous damping; integrated with sub-steps, the table's motion linear over a sample.
struct YieldingSpecimen {
    mass_kg: f64,
    stiffness_n_m: f64,
    damping_n_s_m: f64,
    yield_force_n: f64,
    x_m: f64,
    v_m_s: f64,
    plastic_m: f64,
}

/// Sub-steps of the specimen per sample: a 4-Hz specimen at 512 Hz then takes a
/// thousand steps a cycle.
const SPECIMEN_SUBSTEPS: usize = 8;

impl YieldingSpecimen {
    fn new(mass_kg: f64, frequency_hz: f64, damping_ratio: f64, yield_m: f64) -> Self {
        let w = std::f64::consts::TAU * frequency_hz;
        let k = mass_kg * w * w;
        YieldingSpecimen {
            mass_kg,
            stiffness_n_m: k,
            damping_n_s_m: 2.0 * damping_ratio * mass_kg * w,
            yield_force_n: k * yield_m,
            x_m: 0.0,
            v_m_s: 0.0,
            plastic_m: 0.0,
        }
    }

    /// The spring's force on the specimen's mass for a table at `x`, the plastic drift
    /// updated when it yields.
    fn spring_n(&mut self, x: f64) -> f64 {
        let trial = self.stiffness_n_m * (self.x_m - x - self.plastic_m);
        if trial.abs() > self.yield_force_n {
            let excess = (trial.abs() - self.yield_force_n) * trial.signum();
            self.plastic_m += excess / self.stiffness_n_m;
        }
        self.stiffness_n_m * (self.x_m - x - self.plastic_m)
    }
}

impl Body for YieldingSpecimen {
    fn force_n(&self, x: f64, v: f64) -> f64 {
        self.stiffness_n_m * (self.x_m - x - self.plastic_m) + self.damping_n_s_m * (self.v_m_s - v)
    }

    fn advance(&mut self, x: f64, v: f64, dt: f64) {
        let h = dt / SPECIMEN_SUBSTEPS as f64;
        for j in 0..SPECIMEN_SUBSTEPS {
            let xt = x + v * h * j as f64;
            let f = self.spring_n(xt) + self.damping_n_s_m * (self.v_m_s - v);
            // semi-implicit Euler: stable for an oscillator at this step
            self.v_m_s -= h * f / self.mass_kg;
            self.x_m += h * self.v_m_s;
        }
    }
}

/// Simulate one test with `body` on the table: the truth at every sample (the
/// controller seeing `noise`, as in synthesis), or the reason it stopped.
fn simulate_with_body(
    model: &Model,
    inputs: &[Inputs],
    fs: f64,
    noise: &[SensorNoise],
    max_substep_s: f64,
    body: &mut dyn Body,
) -> Result<Vec<Outputs>, String> {
    let mut sim = Simulator::new(model.clone(), 0.0, max_substep_s);
    let zero = SensorNoise::default();
    let dt = 1.0 / fs;
    let mut out = Vec::with_capacity(inputs.len());
    for k in 0..inputs.len() {
        let bare = sim.outputs(&inputs[k], &zero);
        let (x, v) = (bare.displacement_m, bare.velocity_m_s);
        let f = body.force_n(x, v);
        let now = Inputs {
            external_force_n: f,
            ..inputs[k]
        };
        out.push(sim.outputs(&now, &noise[k]));
        if k + 1 < inputs.len() {
            let next = Inputs {
                external_force_n: f,
                ..inputs[k + 1]
            };
            sim.advance(dt, &now, &next, &noise[k]);
            sim.time_s = (k + 1) as f64 * dt;
            if let Some(why) = sim.diverged() {
                return Err(format!("at {:.3} s: {why}", sim.time_s));
            }
            body.advance(x, v, dt);
        }
    }
    Ok(out)
}

/// The laws by name, each at its default strength times `scale`:
/// - `none`: no force (the campaign `campaign synth` writes; a check of this module);
/// - `quadratic_damping`: a drag `-c v|v|` (air or oil drag, a fluid damper), 5 kN at
///   0.3 m/s, about the friction's amplitude;
/// - `cubic_spring`: a hardening restoring force `-k x^3` (hoses, cables, bearings), 10 kN
///   at 50 mm;
/// - `yielding_specimen`: 15 t at 4 Hz with 3 % damping whose spring yields at 5 mm of
///   drift (elastic-perfectly-plastic; `scale` scales the yield drift): the catalogue's
///   linear specimen past its yield force.
pub fn body(law: &str, scale: f64) -> Box<dyn Body> {
    match law {
        "none" => Box::new(QuadraticDamping { c_n_s2_m2: 0.0 }),
        "quadratic_damping" => Box::new(QuadraticDamping {
            c_n_s2_m2: scale * 5000.0 / 0.09,
        }),
        "cubic_spring" => Box::new(CubicSpring {
            k_n_m3: scale * 10_000.0 / 0.05f64.powi(3),
        }),
        "yielding_specimen" => Box::new(YieldingSpecimen::new(15_000.0, 4.0, 0.03, scale * 0.005)),
        _ => {
            panic!("unknown law {law}: none, quadratic_damping, cubic_spring or yielding_specimen")
        }
    }
}

/// Synthesise the paper's program with `opts` on the table `params` (catalogue effects
/// included), each test with a fresh body of `law` at `scale` on it, and write it into
/// `dir` (with the law's name in [`LAW_FILE`]; the truth file holds `params` only).
pub fn synthesise_with_body(
    params: &Params,
    law: &str,
    scale: f64,
    opts: &SynthOptions,
    dir: &Path,
) {
    let params = *params;
    let program = selected_program(opts);
    let mut c = synthesise_program(&params, &program, opts, None).expect("synthesis");
    let fs = c.info.sample_rate_hz;
    for (j, (i, spec)) in program.iter().enumerate() {
        let t = synthesise_test(&params, spec, *i, opts, fs).expect("test");
        let mut p = params;
        p.controller = spec.controller.apply(&params.controller);
        let inputs = reference(spec, *i, opts.seed, opts.random_duration_s, fs)
            .expect("reference")
            .inputs();
        let model = Model::new(&p);
        let truth = simulate_with_body(
            &model,
            &inputs,
            fs,
            &t.noise,
            opts.max_substep_s,
            body(law, scale).as_mut(),
        )
        .unwrap_or_else(|e| panic!("{}: {e}", spec.name));
        replace_readings(&mut c.records[j], &truth, &t);
    }
    write_synthetic(&c, &params, opts, dir).expect("write");
    std::fs::write(dir.join(LAW_FILE), format!("{law} x {scale}\n")).expect("law file");
}

/// The file naming the law a campaign was made with.
pub const LAW_FILE: &str = "unknown_physics.txt";

/// `r`'s measured channels from `truth` plus the synthesis' own noise samples.
fn replace_readings(r: &mut Record, truth: &[Outputs], t: &SynthTest) {
    let with_noise = |f: &dyn Fn(&Outputs, &SensorNoise) -> f64| {
        truth
            .iter()
            .zip(&t.noise)
            .map(|(o, e)| f(o, e))
            .collect::<Vec<f64>>()
    };
    r.valve_command = Some(truth.iter().map(|o| o.valve_command).collect());
    r.spool_position = Some(
        truth
            .iter()
            .zip(&t.spool_noise)
            .map(|(o, e)| o.spool_position + e)
            .collect(),
    );
    r.displacement_m = Some(with_noise(&|o, e| o.displacement_m + e.displacement_m));
    r.acceleration_m_s2 = Some(with_noise(&|o, e| {
        o.acceleration_m_s2 + e.acceleration_m_s2
    }));
    r.force_n = Some(with_noise(&|o, e| o.actuator_force_n + e.force_n));
    // the synthesis' extra truths (velocity, pressures) belong to the run without the body
    r.extra.clear();
}
