//! Diagnosis: what the identified baseline misses, which catalogue effect (spec section 7)
//! causes it, the effect's parameters, and the gain on tests it was not fitted on.
//!
//! Method:
//! 1. Baseline from [`crate::identify`] (structure from the data: valve order from the
//!    valve FRF, actuator by validation), refined by output-error least squares on the
//!    fitting tests (mass, bulk modulus, leakage, friction; the valve keeps its direct
//!    estimate).
//! 2. Noise floor per channel from the data: the rest segment at the start of each test
//!    (zero reference; median over tests), never from the generator's settings.
//! 3. Normalised residuals (residual RMS / noise RMS) per test and channel.
//! 4. Each catalogue effect fitted by output-error least squares over the fitting tests
//!    where its signature lives, with the interacting baseline parameters free, from
//!    physically informed starts (FRF fits for specimen and foundation, the velocity
//!    plateau for flow saturation, small grids for the friction and deadband).
//! 5. Every candidate and the baseline scored on the held-out tests (the other half of
//!    the program); the best candidate is the cause when it improves the held-out
//!    residual by at least [`REQUIRED_GAIN`]; `explained` when its held-out residual is
//!    within [`EXPLAINED_RATIO`] of the noise floor.

use crate::campaign::{Campaign, Record, TestKind};
use crate::identify::frf::{Welch, WelchOptions};
use crate::identify::lsq::{minimise, LsqOptions};
use crate::identify::{identify, Identification};
use crate::params::{ActuatorModel, Params, ServovalveModel};
use crate::solver::{simulate_record, DEFAULT_MAX_SUBSTEP_S};
use crate::{Model, Outputs};
use num_complex::Complex64;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// A candidate must divide the baseline's held-out residual by at least this to be named.
pub const REQUIRED_GAIN: f64 = 1.25;
/// Held-out residual (RMS over channels and tests, in noise units) at or below which the
/// extended model counts as explaining the data.
pub const EXPLAINED_RATIO: f64 = 2.0;
/// Baseline held-out residual below which the data is at the noise floor (`none`).
pub const FLOOR_RATIO: f64 = 1.3;

/// The compared channels.
pub const CHANNELS: [&str; 5] = [
    "displacement",
    "acceleration",
    "force",
    "spool",
    "valve_command",
];

/// Tests the candidates are fitted on; the rest of the program is held out.
pub const FIT_TESTS: [&str; 9] = ["R2", "S1", "S3", "S5", "S7", "S9", "T1", "T3", "T5"];

/// Catalogue effects (spec section 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    Specimen,
    Foundation,
    StickSlip,
    FlowSaturation,
    ValveDeadband,
}

pub const EFFECTS: [Effect; 5] = [
    Effect::Specimen,
    Effect::Foundation,
    Effect::StickSlip,
    Effect::FlowSaturation,
    Effect::ValveDeadband,
];

impl Effect {
    pub fn name(self) -> &'static str {
        match self {
            Effect::Specimen => "specimen",
            Effect::Foundation => "foundation",
            Effect::StickSlip => "stick_slip",
            Effect::FlowSaturation => "flow_saturation",
            Effect::ValveDeadband => "valve_deadband",
        }
    }

    /// Parameter names (spec section 7).
    pub fn parameters(self) -> &'static [&'static str] {
        match self {
            Effect::Specimen | Effect::Foundation => &["mass_kg", "frequency_hz", "damping_ratio"],
            Effect::StickSlip => &["static_ratio", "stribeck_velocity_m_s"],
            Effect::FlowSaturation => &["max_flow_m3_s"],
            Effect::ValveDeadband => &["deadband"],
        }
    }

    /// The fitting tests where its signature lives.
    fn signature_tests(self) -> &'static [&'static str] {
        match self {
            Effect::Specimen | Effect::Foundation => &["R2", "S3"],
            Effect::StickSlip => &["S1", "S5", "T1", "T3"],
            Effect::FlowSaturation => &["S3", "S9", "R2"],
            Effect::ValveDeadband => &["R2", "T1", "T3", "S1"],
        }
    }

    /// Switch the effect on in `p` with its parameters `theta`.
    fn apply(self, p: &mut Params, theta: &[f64]) {
        match self {
            Effect::Specimen => {
                p.specimen.enabled = true;
                p.specimen.mass_kg = theta[0];
                p.specimen.frequency_hz = theta[1];
                p.specimen.damping_ratio = theta[2];
            }
            Effect::Foundation => {
                p.foundation.enabled = true;
                p.foundation.mass_kg = theta[0];
                p.foundation.frequency_hz = theta[1];
                p.foundation.damping_ratio = theta[2];
            }
            Effect::StickSlip => {
                p.stick_slip.enabled = true;
                p.stick_slip.static_ratio = theta[0];
                p.stick_slip.stribeck_velocity_m_s = theta[1];
            }
            Effect::FlowSaturation => {
                p.flow_saturation.enabled = true;
                p.flow_saturation.max_flow_m3_s = theta[0];
            }
            Effect::ValveDeadband => {
                p.valve_deadband.enabled = true;
                p.valve_deadband.deadband = theta[0];
            }
        }
    }

    /// Baseline parameters left free with the effect (indices into the refined baseline
    /// `[M, beta, C_l, F_mu]`): those it interacts with and its tests constrain.
    fn free_baseline(self) -> &'static [usize] {
        match self {
            // the identified mass holds the specimen's; the oil column moves with both
            Effect::Specimen | Effect::Foundation => &[0, 1, 2],
            // slow tests: only the friction amplitude is seen
            Effect::StickSlip => &[3],
            Effect::FlowSaturation => &[0, 1],
            Effect::ValveDeadband => &[3],
        }
    }

    fn bounds(self) -> (Vec<f64>, Vec<f64>) {
        match self {
            Effect::Specimen => (vec![200.0, 0.5, 0.002], vec![2e5, 60.0, 0.5]),
            Effect::Foundation => (vec![1e4, 2.0, 0.002], vec![1e8, 100.0, 0.5]),
            Effect::StickSlip => (vec![1.0, 1e-4], vec![6.0, 0.05]),
            Effect::FlowSaturation => (vec![1e-4], vec![1.0]),
            Effect::ValveDeadband => (vec![0.0], vec![0.2]),
        }
    }
}

/// Noise RMS per channel, estimated from the data.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct NoiseFloor {
    pub displacement_m: f64,
    pub acceleration_m_s2: f64,
    pub force_n: f64,
    pub spool: f64,
    /// The controller's response to the feedback noise: `sqrt((Kp s_x)^2 + (Ka s_a)^2 +
    /// (Kdp s_F)^2)` (the command itself is recorded without measurement noise).
    pub valve_command: f64,
    /// How it was estimated.
    pub method: &'static str,
}

impl NoiseFloor {
    fn of(&self, channel: usize) -> f64 {
        [
            self.displacement_m,
            self.acceleration_m_s2,
            self.force_n,
            self.spool,
            self.valve_command,
        ][channel]
    }
}

fn std_dev(x: &[f64]) -> f64 {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Noise RMS of every channel from the rest segments (zero reference) at the start of the
/// tests; the high-frequency content (standard deviation of the second difference over
/// sqrt 6) when no test has a rest segment of 64 samples or more.
pub fn estimate_noise(c: &Campaign) -> NoiseFloor {
    let mut per: [Vec<f64>; 4] = Default::default();
    for r in &c.records {
        let rest = (0..r.len())
            .take_while(|&k| {
                r.ref_displacement_m[k] == 0.0
                    && r.ref_velocity_m_s[k] == 0.0
                    && r.ref_acceleration_m_s2[k] == 0.0
            })
            .count();
        if rest >= 64 {
            per[0].push(std_dev(&r.displacement_m[..rest]));
            per[1].push(std_dev(&r.acceleration_m_s2[..rest]));
            per[2].push(std_dev(&r.force_n[..rest]));
            if let Some(s) = &r.spool_position {
                per[3].push(std_dev(&s[..rest]));
            }
        }
    }
    let method;
    let [sx, sa, sf, ss] = if per[0].is_empty() {
        method = "second difference (no rest segment)";
        let d2 = |x: &[f64]| {
            std_dev(
                &x.windows(3)
                    .map(|w| w[0] - 2.0 * w[1] + w[2])
                    .collect::<Vec<_>>(),
            ) / 6f64.sqrt()
        };
        let m =
            |f: &dyn Fn(&Record) -> Option<f64>| median(c.records.iter().filter_map(f).collect());
        [
            m(&|r| Some(d2(&r.displacement_m))),
            m(&|r| Some(d2(&r.acceleration_m_s2))),
            m(&|r| Some(d2(&r.force_n))),
            m(&|r| r.spool_position.as_deref().map(d2)),
        ]
    } else {
        method = "rest segments (zero reference) at the start of the tests";
        [
            median(per[0].clone()),
            median(per[1].clone()),
            median(per[2].clone()),
            median(per[3].clone()),
        ]
    };
    let k = &c.info.controller;
    // floors so that a noise-free record does not divide by zero
    let sx = sx.max(1e-9);
    let sa = sa.max(1e-6);
    let sf = sf.max(1e-3);
    let ss = if ss.is_finite() {
        ss.max(1e-7)
    } else {
        f64::NAN
    };
    let su = ((k.kp * sx).powi(2) + (k.ka * sa).powi(2) + (k.kdp * sf).powi(2))
        .sqrt()
        .max(1e-7);
    NoiseFloor {
        displacement_m: sx,
        acceleration_m_s2: sa,
        force_n: sf,
        spool: ss,
        valve_command: su,
        method,
    }
}

/// Simulate test `i` of the campaign with `p` and the test's controller gains.
pub fn simulate_test(p: &Params, c: &Campaign, i: usize) -> Vec<Outputs> {
    let mut q = *p;
    q.controller = c.controller_for(&c.info.tests[i]);
    simulate_record(
        &Model::new(&q),
        &c.records[i].inputs(),
        c.info.sample_rate_hz,
        None,
        DEFAULT_MAX_SUBSTEP_S,
    )
}

fn measured(r: &Record, ch: usize) -> Option<&[f64]> {
    match ch {
        0 => Some(&r.displacement_m),
        1 => Some(&r.acceleration_m_s2),
        2 => Some(&r.force_n),
        3 => r.spool_position.as_deref(),
        _ => Some(&r.valve_command),
    }
}

fn simulated(o: &Outputs, ch: usize) -> f64 {
    match ch {
        0 => o.displacement_m,
        1 => o.acceleration_m_s2,
        2 => o.actuator_force_n,
        3 => o.spool_position,
        _ => o.valve_command,
    }
}

/// Normalised residual RMS per channel (NaN where the channel is absent).
fn ratios(r: &Record, sim: &[Outputs], noise: &NoiseFloor) -> [f64; 5] {
    let mut out = [f64::NAN; 5];
    for (ch, o) in out.iter_mut().enumerate() {
        if let Some(m) = measured(r, ch) {
            let s = noise.of(ch);
            if s.is_finite() {
                let ss: f64 = m
                    .iter()
                    .zip(sim)
                    .map(|(a, b)| (a - simulated(b, ch)).powi(2))
                    .sum();
                *o = (ss / m.len().max(1) as f64).sqrt() / s;
            }
        }
    }
    out
}

/// Normalised residual samples of `tests` for least squares (every `step`-th sample,
/// scaled so that the cost is the mean squared ratio per test and channel).
fn residual_vector(
    p: &Params,
    c: &Campaign,
    tests: &[usize],
    noise: &NoiseFloor,
    step: usize,
) -> Option<Vec<f64>> {
    if p.validate().is_err() {
        return None;
    }
    let parts: Vec<Vec<f64>> = tests
        .par_iter()
        .map(|&i| {
            let sim = simulate_test(p, c, i);
            let r = &c.records[i];
            let mut v = Vec::new();
            for ch in 0..CHANNELS.len() {
                if let Some(m) = measured(r, ch) {
                    let s = noise.of(ch);
                    if !s.is_finite() {
                        continue;
                    }
                    let n = (m.len() / step).max(1) as f64;
                    let w = 1.0 / (s * n.sqrt());
                    for k in (0..m.len()).step_by(step) {
                        v.push((m[k] - simulated(&sim[k], ch)) * w);
                    }
                }
            }
            v
        })
        .collect();
    let v: Vec<f64> = parts.into_iter().flatten().collect();
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// RMS over tests and channels of the normalised residual ratios.
fn summary(rows: &[[f64; 5]]) -> f64 {
    let v: Vec<f64> = rows
        .iter()
        .flatten()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// The baseline parameters refined by output error, as a vector: `[M, beta, C_l, F_mu]`.
/// The servovalve is not refined: its FRF (command -> spool) is measured directly and no
/// table-side effect changes it, while output error would bend it to absorb them.
fn baseline_theta(p: &Params) -> Vec<f64> {
    vec![
        p.table.mass_kg,
        p.actuator.bulk_modulus_pa,
        p.actuator.leakage_m3_s_pa,
        p.friction.force_n,
    ]
}

fn set_baseline(p: &mut Params, t: &[f64]) {
    p.table.mass_kg = t[0];
    p.actuator.bulk_modulus_pa = t[1];
    p.actuator.leakage_m3_s_pa = t[2];
    p.friction.force_n = t[3];
}

fn baseline_bounds(p: &Params) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let t = baseline_theta(p);
    let lo: Vec<f64> = t.iter().map(|x| x * 0.5).collect();
    let hi: Vec<f64> = t.iter().map(|x| x * 2.0).collect();
    let mut lo = lo;
    lo[2] = 0.0;
    lo[3] = 0.0;
    let scale: Vec<f64> = t.iter().map(|x| x.abs().max(1e-12)).collect();
    (lo, hi, scale)
}

/// A fitted candidate effect.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    pub effect: Effect,
    pub parameters: BTreeMap<String, f64>,
    /// RMS normalised residual on the held-out tests.
    pub heldout_residual: f64,
    /// Held-out residual times a penalty of 1 % per extra parameter (lower is better).
    pub score: f64,
    pub fit_residual: f64,
    #[serde(skip)]
    pub params: Params,
    /// Held-out residual ratios per test and channel.
    #[serde(skip)]
    pub heldout_rows: Vec<[f64; 5]>,
}

/// The whole diagnosis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    pub identification: Identification,
    pub baseline: Params,
    pub noise: NoiseFloor,
    /// Per test (campaign order) and channel.
    pub baseline_rows: Vec<(String, [f64; 5])>,
    pub baseline_heldout: f64,
    pub candidates: Vec<Candidate>,
    pub cause: Option<Effect>,
    pub explained: bool,
    pub gain: f64,
    pub extended: Params,
    pub fit_tests: Vec<String>,
    pub heldout_tests: Vec<String>,
    pub valve_model: ServovalveModel,
    pub actuator_model: ActuatorModel,
    /// Output-error cost of the refined baseline with the ideal and nonlinear actuator.
    pub actuator_costs: [f64; 2],
}

fn indices(c: &Campaign, names: &[&str]) -> Vec<usize> {
    names
        .iter()
        .filter_map(|n| c.info.tests.iter().position(|t| t.name == *n))
        .collect()
}

/// Apparent mass `F/a` of R2 (reference acceleration as instrument) on 1-40 Hz.
fn apparent_mass(c: &Campaign) -> Option<(Vec<f64>, Vec<Complex64>)> {
    let (_, r) = c.test("R2").or_else(|| c.test("R3"))?;
    let fs = c.info.sample_rate_hz;
    let w = Welch::new(
        fs,
        WelchOptions::for_resolution(fs, 0.25).fit_to(r.len(), 8),
    )
    .ok()?;
    let e = w
        .frf_instrumental(&r.ref_acceleration_m_s2, &r.acceleration_m_s2, &r.force_n)
        .ok()?;
    let idx = e.band(1.0, 40.0);
    Some((
        idx.iter().map(|&i| e.frequency_hz[i]).collect(),
        idx.iter().map(|&i| e.h1[i]).collect(),
    ))
}

/// Starting points of a candidate's effect parameters (physically informed).
fn starts(effect: Effect, c: &Campaign, base: &Params) -> Vec<Vec<f64>> {
    let m = base.table.mass_kg;
    match effect {
        Effect::Specimen => {
            // the specimen's resonance is the largest deviation of F/a from a rigid mass
            let Some((f, h)) = apparent_mass(c) else {
                return vec![vec![0.2 * m, 5.0, 0.03]];
            };
            let k = (0..f.len())
                .max_by(|&a, &b| (h[a] - m).norm().total_cmp(&(h[b] - m).norm()))
                .unwrap_or(0);
            let fs = f[k];
            [0.1, 0.3].iter().map(|r| vec![r * m, fs, 0.03]).collect()
        }
        Effect::Foundation => {
            // the foundation moves the LVDT: x_f = a/(-w^2) - x_lvdt; F/x_f = -(k_f - M_f w^2 + j w c_f)
            let guess = foundation_guess(c).unwrap_or([5e5, 20.0, 0.05]);
            vec![guess.to_vec()]
        }
        Effect::StickSlip => vec![vec![2.0, 0.003], vec![3.0, 0.006]],
        Effect::FlowSaturation => {
            // the velocity plateau of the fastest sines
            let mut vmax: f64 = 0.0;
            for (spec, r) in c.info.tests.iter().zip(&c.records) {
                if spec.kind == TestKind::Sine {
                    let fs = c.info.sample_rate_hz;
                    for k in 8..r.len() {
                        vmax = vmax.max(
                            ((r.displacement_m[k] - r.displacement_m[k - 8]) * fs / 8.0).abs(),
                        );
                    }
                }
            }
            let q = vmax * base.actuator.piston_area_m2;
            vec![vec![q.max(1e-3)]]
        }
        Effect::ValveDeadband => vec![vec![0.01], vec![0.03]],
    }
}

/// Linear least squares for the foundation from R2 (see [`starts`]).
fn foundation_guess(c: &Campaign) -> Option<[f64; 3]> {
    let (_, r) = c.test("R2")?;
    let fs = c.info.sample_rate_hz;
    let w = Welch::new(
        fs,
        WelchOptions::for_resolution(fs, 0.25).fit_to(r.len(), 8),
    )
    .ok()?;
    let fa = w
        .frf_instrumental(&r.ref_acceleration_m_s2, &r.acceleration_m_s2, &r.force_n)
        .ok()?;
    let fx = w
        .frf_instrumental(&r.ref_acceleration_m_s2, &r.displacement_m, &r.force_n)
        .ok()?;
    let idx = fa.band(3.0, 60.0);
    let mut a = nalgebra::DMatrix::zeros(2 * idx.len(), 3);
    let mut b = nalgebra::DVector::zeros(2 * idx.len());
    for (row, &i) in idx.iter().enumerate() {
        let om = 2.0 * PI * fa.frequency_hz[i];
        // x_f per unit force: (1/(-w^2)) / (F/a) - 1/(F/x)
        let xf = 1.0 / (-om * om * fa.h1[i]) - 1.0 / fx.h1[i];
        let g = -1.0 / xf; // = k_f - M_f w^2 + j w c_f
        a[(2 * row, 0)] = 1.0;
        a[(2 * row, 1)] = -om * om;
        b[2 * row] = g.re;
        a[(2 * row + 1, 2)] = om;
        b[2 * row + 1] = g.im;
    }
    let (x, _) = crate::identify::lsq::linear(&a, &b)?;
    let (kf, mf, cf) = (x[0], x[1], x[2]);
    if !(kf > 0.0 && mf > 0.0) {
        return None;
    }
    let wf = (kf / mf).sqrt();
    Some([
        mf,
        wf / (2.0 * PI),
        (cf / (2.0 * mf * wf)).clamp(0.005, 0.4),
    ])
}

/// Progress callback: (step done, steps in all, what).
pub type Progress<'a> = &'a (dyn Fn(usize, usize, &str) + Sync);

/// Diagnose a campaign (see the module doc).
pub fn diagnose(c: &Campaign, progress: Option<Progress>) -> Diagnosis {
    let tick = |i: usize, what: &str| {
        if let Some(p) = progress {
            p(i, 8, what);
        }
    };
    tick(0, "identifying the baseline");
    let id = identify(c);
    let noise = estimate_noise(c);
    let mut base = id.params;
    let fit_idx = indices(c, &FIT_TESTS);
    let heldout_idx: Vec<usize> = (0..c.info.tests.len())
        .filter(|i| !fit_idx.contains(i))
        .collect();
    let opts = LsqOptions {
        max_iterations: 12,
        tolerance: 1e-4,
        step: 1e-4,
        parallel: false,
    };
    // 1. refine the baseline by output error on the fitting tests, for both actuator
    //    variants; the one that fits better is the baseline's structure
    tick(1, "refining the baseline by output error");
    let step = 4;
    let refine = |model: ActuatorModel| -> (f64, Params) {
        let mut b0 = base;
        b0.actuator.model = model;
        let (lo, hi, scale) = baseline_bounds(&b0);
        match minimise(
            |t| {
                let mut p = b0;
                set_baseline(&mut p, t);
                residual_vector(&p, c, &fit_idx, &noise, step)
            },
            &baseline_theta(&b0),
            &lo,
            &hi,
            &scale,
            opts,
        ) {
            Some(fit) => {
                set_baseline(&mut b0, &fit.theta);
                (fit.cost, b0)
            }
            None => (f64::INFINITY, b0),
        }
    };
    let (ideal, nonlinear) = rayon::join(
        || refine(ActuatorModel::Ideal),
        || refine(ActuatorModel::Nonlinear),
    );
    let actuator_costs = [ideal.0, nonlinear.0];
    base = if nonlinear.0 < ideal.0 {
        nonlinear.1
    } else {
        ideal.1
    };
    // 2. baseline residuals, every test
    let baseline_rows: Vec<(String, [f64; 5])> = (0..c.records.len())
        .into_par_iter()
        .map(|i| {
            (
                c.info.tests[i].name.clone(),
                ratios(&c.records[i], &simulate_test(&base, c, i), &noise),
            )
        })
        .collect();
    let held = |rows: &[(String, [f64; 5])]| -> Vec<[f64; 5]> {
        heldout_idx.iter().map(|&i| rows[i].1).collect()
    };
    let baseline_heldout = summary(&held(&baseline_rows));
    // 3. candidates
    let done = std::sync::atomic::AtomicUsize::new(2);
    let candidates: Vec<Candidate> = EFFECTS
        .par_iter()
        .filter_map(|&e| {
            let cand = fit_candidate(e, c, &base, &fit_idx, &heldout_idx, &noise, opts, step);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            tick(n + 1, e.name());
            cand
        })
        .collect();
    let best = candidates
        .iter()
        .min_by(|a, b| a.score.total_cmp(&b.score))
        .cloned();
    let (cause, extended, ext_resid) = match &best {
        Some(b)
            if baseline_heldout > FLOOR_RATIO
                && baseline_heldout / b.heldout_residual >= REQUIRED_GAIN =>
        {
            (Some(b.effect), b.params, b.heldout_residual)
        }
        _ => (None, base, baseline_heldout),
    };
    let gain = baseline_heldout / ext_resid;
    let explained = ext_resid <= EXPLAINED_RATIO;
    Diagnosis {
        baseline: base,
        noise,
        baseline_rows,
        baseline_heldout,
        candidates,
        cause,
        explained,
        gain,
        extended,
        fit_tests: fit_idx
            .iter()
            .map(|&i| c.info.tests[i].name.clone())
            .collect(),
        heldout_tests: heldout_idx
            .iter()
            .map(|&i| c.info.tests[i].name.clone())
            .collect(),
        valve_model: id.params.servovalve.model,
        actuator_model: base.actuator.model,
        actuator_costs,
        identification: id,
    }
}

#[allow(clippy::too_many_arguments)]
fn fit_candidate(
    e: Effect,
    c: &Campaign,
    base: &Params,
    fit_idx: &[usize],
    heldout_idx: &[usize],
    noise: &NoiseFloor,
    opts: LsqOptions,
    step: usize,
) -> Option<Candidate> {
    let sig: Vec<usize> = indices(c, e.signature_tests())
        .into_iter()
        .filter(|i| fit_idx.contains(i))
        .collect();
    if sig.is_empty() {
        return None;
    }
    let ne = e.parameters().len();
    let free = e.free_baseline();
    let (elo, ehi) = e.bounds();
    let (blo, bhi, bscale) = baseline_bounds(base);
    let b_all = baseline_theta(base);
    let assemble = |t: &[f64]| {
        let mut p = *base;
        e.apply(&mut p, &t[..ne]);
        let mut b = b_all.clone();
        for (k, &j) in free.iter().enumerate() {
            b[j] = t[ne + k];
        }
        set_baseline(&mut p, &b);
        p
    };
    let lo: Vec<f64> = elo
        .iter()
        .copied()
        .chain(free.iter().map(|&j| blo[j]))
        .collect();
    let hi: Vec<f64> = ehi
        .iter()
        .copied()
        .chain(free.iter().map(|&j| bhi[j]))
        .collect();
    let mut best: Option<(f64, Vec<f64>)> = None;
    for s in starts(e, c, base) {
        let mut b = b_all.clone();
        if e == Effect::Specimen {
            // the identified mass holds the specimen's mass at low frequency
            b[0] = (b[0] - s[0]).max(0.3 * b[0]);
        }
        let t0: Vec<f64> = s
            .iter()
            .copied()
            .chain(free.iter().map(|&j| b[j]))
            .collect();
        let scale: Vec<f64> = s
            .iter()
            .map(|x| x.abs().max(1e-4))
            .chain(free.iter().map(|&j| bscale[j]))
            .collect();
        if let Some(f) = minimise(
            |t| residual_vector(&assemble(t), c, &sig, noise, step),
            &t0,
            &lo,
            &hi,
            &scale,
            opts,
        ) {
            if best.as_ref().map(|b| f.cost < b.0).unwrap_or(true) {
                best = Some((f.cost, f.theta));
            }
        }
    }
    let (cost, theta) = best?;
    let p = assemble(&theta);
    let rows: Vec<[f64; 5]> = heldout_idx
        .par_iter()
        .map(|&i| ratios(&c.records[i], &simulate_test(&p, c, i), noise))
        .collect();
    let heldout = summary(&rows);
    Some(Candidate {
        effect: e,
        parameters: e
            .parameters()
            .iter()
            .zip(&theta)
            .map(|(k, v)| (k.to_string(), *v))
            .collect(),
        heldout_residual: heldout,
        score: heldout * (1.0 + 0.01 * ne as f64),
        fit_residual: cost.sqrt(),
        params: p,
        heldout_rows: rows,
    })
}

impl Diagnosis {
    /// The JSON of issue 6 (fixed keys).
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::json;
        let cause = self.cause.map(|e| e.name()).unwrap_or("none");
        let parameters = match self
            .cause
            .and_then(|e| self.candidates.iter().find(|c| c.effect == e))
        {
            Some(c) => json!(c.parameters),
            None => json!({}),
        };
        let mut base = serde_json::Map::new();
        for (name, r) in &self.baseline_rows {
            let mut m = serde_json::Map::new();
            for (ch, v) in CHANNELS.iter().zip(r) {
                if v.is_finite() {
                    m.insert(ch.to_string(), json!(v));
                }
            }
            base.insert(name.clone(), serde_json::Value::Object(m));
        }
        json!({
            "cause": cause,
            "parameters": parameters,
            "gain": self.gain,
            "explained": self.explained,
            "baseline_residuals": base,
            "baseline_heldout_residual": self.baseline_heldout,
            "candidates": self.candidates.iter().map(|c| json!({
                "effect": c.effect.name(),
                "parameters": c.parameters,
                "heldout_residual": c.heldout_residual,
                "score": c.score,
            })).collect::<Vec<_>>(),
            "noise": self.noise,
            "fit_tests": self.fit_tests,
            "heldout_tests": self.heldout_tests,
            "baseline_structure": {
                "servovalve": self.valve_model.name(),
                "actuator": self.actuator_model.name(),
            },
            "rule": format!("cause = the candidate with the lowest held-out residual (1 % penalty per parameter) when the baseline's held-out residual exceeds {FLOOR_RATIO} noise RMS and the candidate divides it by >= {REQUIRED_GAIN}; explained when the extended held-out residual <= {EXPLAINED_RATIO} noise RMS"),
        })
    }
}
