//! Stiffness and sliding friction from the triangles (paper 4.2.1) and Bouc-Wen friction
//! from the slow sines (4.2.3, eqs. 4.13-4.15).

use super::error::IdentifyError;
use super::lsq::{minimise, LsqOptions};
use super::results::{FrictionFit, TriangleFit};
use super::signals::{
    correlation_factor, derivative, fourth_difference_rms, monotone_path, smooth,
    MAX_CORRELATION_LAG,
};
use super::{
    check_bounds, check_moved, lsq, MIN_SINE_CYCLES, MIN_TRIANGLE_CYCLES, TRIANGLE_FRACTION,
};
use crate::campaign::{Campaign, Measured, Record, TestSpec};
use nalgebra::{DMatrix, DVector};

/// Mean-removed steady part of a periodic test: samples after the first cycle and
/// before the last, where the amplitude has settled (ramps excluded).
pub(super) fn steady_range(spec: &TestSpec, rec: &Record) -> std::ops::Range<usize> {
    let n = rec.len();
    let x = &rec.ref_displacement_m;
    let amp = spec
        .amplitude_m
        .unwrap_or_else(|| x.iter().fold(0.0, |m: f64, v| m.max(v.abs())));
    // first and last samples where the reference reaches 99 % of the amplitude
    let first = x.iter().position(|v| v.abs() >= 0.99 * amp).unwrap_or(0);
    let last = x.iter().rposition(|v| v.abs() >= 0.99 * amp).unwrap_or(n);
    first..last.max(first)
}

/// Fewest samples away from reversals for the triangles' two-parameter fit.
const MIN_TRIANGLE_SAMPLES: usize = 10;
/// A sample is sliding when its speed exceeds this, m/s (the sign of `v` is the
/// friction's only there).
const SLIDING_SPEED_M_S: f64 = 1e-4;
/// Half-width of the triangles' displacement smoothing before differentiation, samples.
const TRIANGLE_SMOOTHING_HALF_WIDTH: usize = 8;

/// The triangles' force balance away from reversals (eq. 4.9): rows `[x, sign v]`
/// against `F_A - M a`, with the tests used and their steady cycles.
#[derive(Default)]
struct TriangleRows {
    names: Vec<String>,
    cycles: f64,
    rows: Vec<[f64; 2]>,
    rhs: Vec<f64>,
}

impl TriangleRows {
    /// Every triangle test of `c` recording displacement, acceleration and force, with
    /// the table's mass `mass_kg`.
    fn of(c: &Campaign, mass_kg: f64) -> TriangleRows {
        let mut t = TriangleRows::default();
        for (spec, rec) in c.info.tests.iter().zip(&c.records) {
            if spec.kind != crate::campaign::TestKind::Triangle {
                continue;
            }
            let (Some(x_measured), Some(a_measured), Some(force)) = (
                rec.measured(Measured::Displacement),
                rec.measured(Measured::Acceleration),
                rec.measured(Measured::Force),
            ) else {
                continue; // the force balance needs all three
            };
            t.names.push(spec.name.clone());
            let fs = c.sample_rate_for(spec);
            let range = steady_range(spec, rec);
            t.cycles += range.len() as f64 / fs
                * spec.frequency_hz.filter(|f| f.is_finite()).unwrap_or(0.0);
            let amp = spec.amplitude_m.unwrap_or(1.0);
            let xs = smooth(x_measured, TRIANGLE_SMOOTHING_HALF_WIDTH);
            let v = derivative(&xs, fs);
            for i in range {
                let x = rec.ref_displacement_m[i];
                if x.abs() < TRIANGLE_FRACTION * amp && v[i].abs() > SLIDING_SPEED_M_S {
                    t.rows.push([x_measured[i], v[i].signum()]);
                    t.rhs.push(force[i] - mass_kg * a_measured[i]);
                }
            }
        }
        t
    }

    /// Why these rows cannot give the fit, if they cannot.
    fn unusable(&self) -> Option<IdentifyError> {
        if self.names.is_empty() {
            return Some(IdentifyError::not_usable(
                "no triangle test: stiffness and sliding friction not identified from triangles",
            ));
        }
        let cycles = self.cycles;
        if cycles.is_nan() || cycles < MIN_TRIANGLE_CYCLES || self.rows.len() < MIN_TRIANGLE_SAMPLES
        {
            return Some(IdentifyError::not_usable(format!(
                "the triangle tests ({}) hold {cycles:.2} steady cycles and {} samples away from reversals; at least {MIN_TRIANGLE_CYCLES} cycle and {MIN_TRIANGLE_SAMPLES} samples needed: stiffness and sliding friction not identified",
                self.names.join(", "),
                self.rows.len()
            )));
        }
        None
    }
}

/// Triangles (eqs. 4.9-4.10): away from reversals the acceleration is zero and
/// `F_A - M a = k x + F_mu sign(v)`; least squares over every triangle.
pub fn fit_triangles(c: &Campaign, mass_kg: f64) -> Result<TriangleFit, IdentifyError> {
    let t = TriangleRows::of(c, mass_kg);
    if let Some(e) = t.unusable() {
        return Err(e);
    }
    let TriangleRows {
        names, rows, rhs, ..
    } = t;
    let a = DMatrix::from_fn(rows.len(), 2, |i, j| rows[i][j]);
    let b = DVector::from_vec(rhs.clone());
    let (x, sigma) = lsq::linear(&a, &b).ok_or(IdentifyError::not_usable("triangle fit failed"))?;
    let who = names.join(", ");
    check_bounds(&who, "stiffness (N/m)", x[0], [-1e12, 1e12])?;
    check_bounds(&who, "sliding friction (N)", x[1], [-1e9, 1e9])?;
    let step = (rows.len() / 1500).max(1);
    Ok(TriangleFit {
        tests: names,
        stiffness_n_m: x[0],
        sigma_stiffness_n_m: sigma[0],
        sliding_friction_n: x[1],
        displacement_m: rows.iter().step_by(step).map(|r| r[0]).collect(),
        elastic_force_n: rows
            .iter()
            .zip(&rhs)
            .step_by(step)
            .map(|(r, f)| f - x[1] * r[1])
            .collect(),
    })
}

/// Bouc-Wen `Z` along a displacement path (eq. 4.15 is rate independent:
/// `dZ = (1 - Z^2 (b + (1 - b) sign(Z dx))) dx / Y`), sub-stepped for accuracy.
pub fn bouc_wen_path(x: &[f64], yield_m: f64, shape: f64, z0: f64) -> Vec<f64> {
    let mut z = z0;
    let mut out = Vec::with_capacity(x.len());
    out.push(z);
    for i in 1..x.len() {
        let dx = x[i] - x[i - 1];
        let n = ((dx.abs() / (0.2 * yield_m)).ceil() as usize).clamp(1, 1000);
        let h = dx / n as f64;
        for _ in 0..n {
            let s = (z * h).signum();
            z += (1.0 - z * z * (shape + (1.0 - shape) * s)) * h / yield_m;
            z = z.clamp(-1.0, 1.0);
        }
        out.push(z);
    }
    out
}

/// The tests of a list, or what such a test would be when there is none.
pub(super) fn slow_list(names: &[String], none: &str) -> String {
    match names.is_empty() {
        true => format!("no test is {none}"),
        false => names.join(", "),
    }
}

/// Half-width of the displacement's centred moving average, samples (16 ms at 512 Hz,
/// 8 ms at 1 kHz): it cuts the LVDT's white noise by sqrt(17), while a slow sine of the
/// friction fit (inertia at most twice the friction: below about 0.5 Hz on the paper's
/// table) loses less than 0.2 % of its amplitude even at 256 Hz.
const SMOOTHING_HALF_WIDTH: usize = 8;

/// A reversal of the Bouc-Wen path counts once the smoothed displacement comes back by
/// this many of its noise's RMS: the smoothed noise wanders by a few RMS within a
/// reversal's dwell, and a real reversal of a sine runs on by its whole stroke.
const PATH_NOISE_FACTOR: f64 = 5.0;

/// The threshold of [`monotone_path`] for the displacement `raw`: [`PATH_NOISE_FACTOR`]
/// times its white noise after the moving average (the average of `2 h + 1` samples
/// divides the variance by as many).
fn path_threshold(raw: &[f64]) -> f64 {
    let averaged = (2 * SMOOTHING_HALF_WIDTH + 1) as f64;
    let sigma = fourth_difference_rms(raw) / averaged.sqrt();
    if sigma.is_finite() {
        PATH_NOISE_FACTOR * sigma
    } else {
        0.0
    }
}

/// The steady part of a sine test: smoothed displacement and its velocity, measured
/// acceleration and force.
pub(super) struct SineData {
    pub(super) name: String,
    pub(super) x: Vec<f64>,
    /// `x` without its noise's back-and-forth ([`monotone_path`]): what drives the
    /// Bouc-Wen friction (eq. 4.15), which turns at every wiggle of its input.
    pub(super) path: Vec<f64>,
    pub(super) v: Vec<f64>,
    pub(super) a: Vec<f64>,
    pub(super) f: Vec<f64>,
}

/// The sine tests `names` of `c` with at least [`MIN_SINE_CYCLES`] steady cycles; the
/// others are named in the second list with the reason.
pub(super) fn sine_data(c: &Campaign, names: &[&str]) -> (Vec<SineData>, Vec<String>) {
    let mut short = Vec::new();
    let data = names
        .iter()
        .filter_map(|n| c.test(n))
        .filter(|(s, _)| s.kind == crate::campaign::TestKind::Sine)
        .filter(|(spec, rec)| {
            let needs = [Measured::Displacement, Measured::Acceleration, Measured::Force];
            if !rec.has_all(&needs) {
                short.push(format!(
                    "{} ({}): the force balance needs displacement_m, acceleration_m_s2 and \
                     force_n: not used",
                    spec.name, spec.file
                ));
                return false;
            }
            let r = steady_range(spec, rec);
            let f = spec.frequency_hz.filter(|f| f.is_finite()).unwrap_or(0.0);
            let cycles = r.len() as f64 / c.sample_rate_for(spec) * f;
            let ok = cycles >= MIN_SINE_CYCLES;
            if !ok {
                short.push(format!(
                    "{} ({}): {cycles:.2} steady cycles, at least {MIN_SINE_CYCLES} needed: not used",
                    spec.name, spec.file
                ));
            }
            ok
        })
        .map(|(spec, rec)| {
            let r = steady_range(spec, rec);
            // every channel is there: the filter above kept only such tests
            let get = |m| rec.measured(m).unwrap_or_default();
            let raw = get(Measured::Displacement);
            let xs = smooth(raw, SMOOTHING_HALF_WIDTH);
            let v = derivative(&xs, c.sample_rate_for(spec));
            let path = monotone_path(&xs, path_threshold(raw));
            SineData {
                name: spec.name.clone(),
                x: xs[r.clone()].to_vec(),
                path: path[r.clone()].to_vec(),
                v: v[r.clone()].to_vec(),
                a: get(Measured::Acceleration)[r.clone()].to_vec(),
                f: get(Measured::Force)[r].to_vec(),
            }
        })
        .collect();
    (data, short)
}

/// Every this many samples of the dissipative force enters the Bouc-Wen fit: the
/// friction changes over `Y`, well resolved at 128 Hz from 512 Hz.
const BOUC_WEN_DECIMATION: usize = 4;
/// Start of the friction force when the triangles give none, N.
const FRICTION_START_N: f64 = 1000.0;

/// The slow sines' dissipative force `F_D = F_A - M a - k x` (eq. 4.13), what the
/// Bouc-Wen friction `F_mu Z` (eq. 4.14) is fitted to.
struct Dissipative {
    data: Vec<SineData>,
    /// `F_D` of each test of `data`.
    force_n: Vec<Vec<f64>>,
}

impl Dissipative {
    fn of(data: Vec<SineData>, mass_kg: f64, stiffness: f64) -> Dissipative {
        let force_n = data
            .iter()
            .map(|d| {
                (0..d.x.len())
                    .map(|i| d.f[i] - mass_kg * d.a[i] - stiffness * d.x[i])
                    .collect()
            })
            .collect();
        Dissipative { data, force_n }
    }

    /// `F_mu Z - F_D` over every test (decimated), `Z` along each test's path from the
    /// sign of its first velocity with yield `y` and shape `b`.
    fn residuals(&self, fmu: f64, y: f64, b: f64) -> Vec<f64> {
        let mut r = Vec::new();
        for (d, fdi) in self.data.iter().zip(&self.force_n) {
            let z = bouc_wen_path(&d.path, y, b, d.v[0].signum());
            for i in (0..z.len()).step_by(BOUC_WEN_DECIMATION) {
                r.push(fmu * z[i] - fdi[i]);
            }
        }
        r
    }

    /// The tests' names, joined.
    fn names(&self) -> String {
        self.data
            .iter()
            .map(|d| d.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The slow sines `slow` of `c` usable by the friction fit, or why none is.
fn slow_sines(c: &Campaign, slow: &[String]) -> Result<Vec<SineData>, IdentifyError> {
    let names: Vec<&str> = slow.iter().map(String::as_str).collect();
    let (data, short) = sine_data(c, &names);
    if data.is_empty() {
        return Err(IdentifyError::not_usable(format!(
            "no slow sine test ({}) usable: Bouc-Wen friction not identified{}",
            slow_list(
                slow,
                "a sine whose inertia force is at most twice the friction"
            ),
            short.iter().map(|s| format!("; {s}")).collect::<String>()
        )));
    }
    Ok(data)
}

/// Bouc-Wen parameters (eqs. 4.14-4.15) fitted to `F_D = F_A - M a - k x` (eq. 4.13)
/// of the slow sines; `F_mu` enters linearly, `Y` and `b` by Levenberg-Marquardt.
pub fn fit_friction(
    c: &Campaign,
    slow: &[String],
    mass_kg: f64,
    stiffness: f64,
    f_mu0: f64,
) -> Result<FrictionFit, IdentifyError> {
    let fd = Dissipative::of(slow_sines(c, slow)?, mass_kg, stiffness);
    let residual = |p: &[f64]| -> Option<Vec<f64>> { Some(fd.residuals(p[0], p[1], p[2])) };
    let f0 = if f_mu0.is_finite() && f_mu0 > 0.0 {
        f_mu0
    } else {
        FRICTION_START_N
    };
    let (t0, scale) = ([f0, 1e-3, 0.5], [f0, 1e-3, 0.5]);
    let fit = minimise(
        residual,
        &t0,
        &[0.0, 1e-5, 0.0],
        &[1e7, 0.05, 0.999],
        &scale,
        LsqOptions::default(),
    )
    .ok_or(IdentifyError::not_usable("Bouc-Wen fit failed"))?;
    check_moved(&fd.names(), "Bouc-Wen fit", &fit, &t0, &scale)?;
    // the residual is far from white (the table's jitter, the shape's model error at
    // each reversal): the sigmas are widened by its integrated autocorrelation, as the
    // closed loop's and the device's are
    let widen =
        residual(&fit.theta).map_or(1.0, |r| correlation_factor(&r, MAX_CORRELATION_LAG).sqrt());
    Ok(friction_fit(&fd, &fit, widen))
}

/// The result of the Bouc-Wen fit `fit` of `fd`, its sigmas widened by `widen`, with
/// the first test's figure (decimated).
fn friction_fit(fd: &Dissipative, fit: &lsq::LsqFit, widen: f64) -> FrictionFit {
    let (fmu, y, b) = (fit.theta[0], fit.theta[1], fit.theta[2]);
    let d0 = &fd.data[0];
    let z = bouc_wen_path(&d0.path, y, b, d0.v[0].signum());
    let step = (d0.x.len() / 2000).max(1);
    FrictionFit {
        tests: fd.data.iter().map(|d| d.name.clone()).collect(),
        force_n: fmu,
        yield_displacement_m: y,
        shape: b,
        sigma_force_n: widen * fit.sigma[0],
        sigma_yield_displacement_m: widen * fit.sigma[1],
        sigma_shape: widen * fit.sigma[2],
        rms_error_n: (fit.cost / fit.residuals as f64).sqrt(),
        displacement_m: d0.x.iter().step_by(step).copied().collect(),
        velocity_m_s: d0.v.iter().step_by(step).copied().collect(),
        dissipative_force_n: fd.force_n[0].iter().step_by(step).copied().collect(),
        fitted_force_n: z.iter().step_by(step).map(|z| fmu * z).collect(),
    }
}
