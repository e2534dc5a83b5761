//! Synthesis of the paper's test program (R1-R3, S1-S9, T1-T6; campaign-format.md, "The
//! paper's test program") from any parameter set, with seeded sensor noise inside the
//! loop (model spec section 2).
//!
//! Every test has [`REST_S`] of rest (zero reference) at its start and end, so the noise
//! can be estimated from rest segments. References (r, r', r'') are exactly consistent:
//! - random: band-limited white noise made in the frequency domain (random phases, flat
//!   amplitude over the band's FFT bins, no DC) with exact spectral derivatives, times a
//!   raised-cosine fade-in/out of [`FADE_S`] with the derivatives by the product rule,
//!   scaled so the steady part (fade excluded) has the requested RMS of the controlled
//!   quantity (displacement or acceleration);
//! - sine: half-period raised-cosine amplitude ramp-in, steady cycles (at least 2 and at
//!   least 18 s: 2 at 0.05 and 0.1 Hz, 9 at 0.5 Hz), half-period ramp-out; analytic;
//! - triangle: the velocity is a sum of smooth steps `dV S((t - t_k)/Tb)`,
//!   `S(s) = (1 + sin(pi s))/2` on [-1/2, 1/2], Tb = [`BLEND_S`]; closed-form
//!   displacement and acceleration; 3 cycles; `V = A / (T/4 - Tb (1/2 - 1/pi))` so the
//!   peak is exactly the amplitude.
//!
//! With the default 90 s random length the whole program is 906 s of table time.
//!
//! Randomness: one `ChaCha8Rng` per test and purpose, seeded with the campaign seed and
//! the stream `2 i` (reference phases) or `2 i + 1` (sensor noise), `i` the test's index
//! in the program, so tests are independent, run in parallel, and a subset (`--tests`)
//! gives the same records as the full program.

use super::format::{write_campaign, CampaignError};
use super::{
    Campaign, CampaignInfo, Control, ControllerOverride, Geometry, Record, TestKind, TestSpec,
};
use crate::model::{Inputs, Model, Outputs, Reference, SensorNoise};
use crate::output::atomic_write;
use crate::params::Params;
use crate::solver::{simulate_run, DEFAULT_MAX_SUBSTEP_S};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Sample rate of synthetic campaigns (the TREES Lab controller records at 512 Hz).
pub const SAMPLE_RATE_HZ: f64 = 512.0;
/// Rest (zero reference) at the start and at the end of every test, s.
pub const REST_S: f64 = 1.0;
/// Raised-cosine fade-in/out of random references, s.
pub const FADE_S: f64 = 0.5;
/// Reversal blend of triangle references, s.
pub const BLEND_S: f64 = 0.1;
/// Default length of the band-limited part of random tests, s.
pub const DEFAULT_RANDOM_DURATION_S: f64 = 90.0;
/// The parameters used (the truth); identification must never read it.
pub const TRUTH_FILE: &str = "truth.toml";
/// Seed, noise levels and options of the synthesis.
pub const SYNTHESIS_FILE: &str = "synthesis.toml";
/// Longest random part of a random test, s: one hour is longer than any lab test, and
/// keeps a campaign in memory below a few GB (1.8 M samples per random record).
pub const MAX_RANDOM_DURATION_S: f64 = 3600.0;
/// Smallest solver sub-step, s: 33x finer than the default, enough for a convergence
/// check; finer steps only multiply the run time (a campaign would take hours).
pub const MIN_SUBSTEP_S: f64 = 1e-5;

/// Errors in synthesis options.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    #[error("synthesis option `{option}` = {value}: {rule}")]
    Option {
        option: &'static str,
        value: String,
        rule: &'static str,
    },
    #[error("unknown test `{name}`; the program has {known}")]
    UnknownTest { name: String, known: String },
    #[error("test `{name}`: {message}")]
    BadTest { name: String, message: String },
    #[error(transparent)]
    Campaign(#[from] CampaignError),
}

/// White sensor noise levels, RMS, on the four measured channels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseLevels {
    /// Spool position (normalised); measurement only, never fed back.
    pub spool: f64,
    pub displacement_m: f64,
    pub acceleration_m_s2: f64,
    pub force_n: f64,
}

impl Default for NoiseLevels {
    fn default() -> Self {
        NoiseLevels {
            spool: 0.002,
            displacement_m: 2e-5,
            acceleration_m_s2: 0.01,
            force_n: 200.0,
        }
    }
}

impl NoiseLevels {
    /// No noise at all.
    pub fn none() -> Self {
        NoiseLevels {
            spool: 0.0,
            displacement_m: 0.0,
            acceleration_m_s2: 0.0,
            force_n: 0.0,
        }
    }

    fn is_none(&self) -> bool {
        *self == NoiseLevels::none()
    }
}

/// Options of [`synthesise`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SynthOptions {
    pub seed: u64,
    pub noise: NoiseLevels,
    /// Length of the band-limited part of each random test, s (fades included).
    pub random_duration_s: f64,
    /// Largest solver sub-step, s.
    pub max_substep_s: f64,
    /// Only these tests of the program (by name), in program order; `None` = all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tests: Option<Vec<String>>,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            seed: 1,
            noise: NoiseLevels::default(),
            random_duration_s: DEFAULT_RANDOM_DURATION_S,
            max_substep_s: DEFAULT_MAX_SUBSTEP_S,
            tests: None,
        }
    }
}

impl SynthOptions {
    /// Check every option (and that `tests` names tests of the paper program).
    pub fn validate(&self) -> Result<(), SynthError> {
        let bad = |option, value: f64, rule| {
            Err(SynthError::Option {
                option,
                value: value.to_string(),
                rule,
            })
        };
        let n = &self.noise;
        for (name, v) in [
            ("noise.spool", n.spool),
            ("noise.displacement_m", n.displacement_m),
            ("noise.acceleration_m_s2", n.acceleration_m_s2),
            ("noise.force_n", n.force_n),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, v, "must be finite and >= 0");
            }
        }
        let d = self.random_duration_s;
        if !(d.is_finite() && d >= 4.0 * FADE_S) {
            return bad(
                "random_duration_s",
                d,
                "must be at least 2 s (two 0.5 s fades and a steady part)",
            );
        }
        if d > MAX_RANDOM_DURATION_S {
            return bad(
                "random_duration_s",
                d,
                "must be at most 3600 s (MAX_RANDOM_DURATION_S)",
            );
        }
        if !(self.max_substep_s.is_finite() && self.max_substep_s >= MIN_SUBSTEP_S) {
            return bad(
                "max_substep_s",
                self.max_substep_s,
                "must be finite and at least 1e-5 s (MIN_SUBSTEP_S)",
            );
        }
        if let Some(names) = &self.tests {
            let program = paper_program(d);
            for (i, name) in names.iter().enumerate() {
                if !program.iter().any(|t| &t.name == name) {
                    return Err(SynthError::UnknownTest {
                        name: name.clone(),
                        known: program
                            .iter()
                            .map(|t| t.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", "),
                    });
                }
                if names[..i].contains(name) {
                    return Err(SynthError::BadTest {
                        name: name.clone(),
                        message: "listed twice".to_string(),
                    });
                }
            }
        }
        Ok(())
    }
}

/// The file a synthesised test `name` is written to.
fn csv_file(name: &str) -> String {
    format!("{name}.csv")
}

/// The paper's test program (campaign-format.md table; paper tables 4.1-4.3), in order
/// R1-R3, S1-S9, T1-T6. The specs do not depend on `random_duration_s` (it only sets
/// the length of random records, see [`test_duration_s`]); it is taken here so callers
/// state which program they mean.
pub fn paper_program(random_duration_s: f64) -> Vec<TestSpec> {
    let _ = random_duration_s;
    let mut p = Vec::with_capacity(18);
    for (name, control, rms, band_hz) in [
        ("R1", Control::Displacement, 0.005, [0.0, 125.0]),
        ("R2", Control::Acceleration, 0.981, [0.5, 50.0]), // 0.1 g
        ("R3", Control::Acceleration, 0.4905, [0.5, 125.0]), // 0.05 g
    ] {
        p.push(TestSpec::random(
            name,
            csv_file(name),
            control,
            rms,
            band_hz,
        ));
    }
    // R1: a flat displacement spectrum to 125 Hz has r' ~ 2 m/s RMS: with the velocity
    // feed-forward on, the valve would saturate.
    p[0].controller.fv = Some(0.0);
    let mut i = 1;
    for a in [0.05, 0.10, 0.20] {
        for f in [0.05, 0.10, 0.5] {
            let name = format!("S{i}");
            let file = csv_file(&name);
            p.push(TestSpec::periodic(name, file, TestKind::Sine, f, a));
            i += 1;
        }
    }
    let mut i = 1;
    for a in [0.05, 0.10, 0.20] {
        for f in [0.05, 0.10] {
            let name = format!("T{i}");
            let file = csv_file(&name);
            p.push(TestSpec::periodic(name, file, TestKind::Triangle, f, a));
            i += 1;
        }
    }
    p
}

/// Steady cycles of a sine test: at least 2 and at least 18 s.
pub fn sine_cycles(frequency_hz: f64) -> usize {
    ((18.0 * frequency_hz - 1e-9).ceil() as usize).max(2)
}

/// Cycles of a triangle test.
pub const TRIANGLE_CYCLES: usize = 3;

/// Length of a test's record, s (rests included).
pub fn test_duration_s(spec: &TestSpec, random_duration_s: f64) -> f64 {
    let f = spec.frequency_hz.unwrap_or(1.0);
    2.0 * REST_S
        + match spec.kind {
            TestKind::Random => random_duration_s,
            TestKind::Sine => (sine_cycles(f) + 1) as f64 / f,
            TestKind::Triangle => TRIANGLE_CYCLES as f64 / f,
            // never synthesised (check_spec refuses it): no length of its own
            TestKind::Record => 0.0,
        }
}

/// Number of samples of a test's record at `sample_rate_hz`.
pub fn test_samples(spec: &TestSpec, random_duration_s: f64, sample_rate_hz: f64) -> usize {
    (test_duration_s(spec, random_duration_s) * sample_rate_hz).round() as usize
}

/// The three reference channels of a test, sampled.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReferenceSignal {
    pub displacement_m: Vec<f64>,
    pub velocity_m_s: Vec<f64>,
    pub acceleration_m_s2: Vec<f64>,
}

impl ReferenceSignal {
    fn zeros(n: usize) -> Self {
        ReferenceSignal {
            displacement_m: vec![0.0; n],
            velocity_m_s: vec![0.0; n],
            acceleration_m_s2: vec![0.0; n],
        }
    }

    /// The model inputs at every sample (no external force).
    pub fn inputs(&self) -> Vec<Inputs> {
        (0..self.len())
            .map(|k| Inputs {
                reference: Reference {
                    displacement_m: self.displacement_m[k],
                    velocity_m_s: self.velocity_m_s[k],
                    acceleration_m_s2: self.acceleration_m_s2[k],
                },
                external_force_n: 0.0,
            })
            .collect()
    }

    pub fn len(&self) -> usize {
        self.displacement_m.len()
    }

    pub fn is_empty(&self) -> bool {
        self.displacement_m.is_empty()
    }
}

fn check_spec(spec: &TestSpec, random_duration_s: f64, fs: f64) -> Result<(), SynthError> {
    let bad = |m: &str| {
        Err(SynthError::BadTest {
            name: spec.name.clone(),
            message: m.to_string(),
        })
    };
    if !(fs.is_finite() && fs > 0.0) {
        return bad("sample_rate_hz must be finite and > 0");
    }
    match spec.kind {
        TestKind::Record => {
            return bad(
                "a `record` test replays a recorded reference; the synthetic program \
                        generates random, sine and triangle references only",
            )
        }
        TestKind::Random => {
            let (Some(rms), Some([lo, hi])) = (spec.rms, spec.band_hz) else {
                return bad("a random test needs rms and band_hz");
            };
            if !(rms.is_finite() && rms > 0.0) {
                return bad("rms must be finite and > 0");
            }
            if !(lo >= 0.0 && hi > lo && hi < fs / 2.0) {
                return bad("band_hz must satisfy 0 <= low < high < Nyquist");
            }
            let d = (random_duration_s * fs).round() / fs;
            let (k_lo, k_hi) = band_bins(lo, hi, d, (random_duration_s * fs).round() as usize);
            if k_hi < k_lo {
                return bad("band_hz holds no frequency bin of the random record");
            }
            if !(random_duration_s.is_finite() && random_duration_s >= 4.0 * FADE_S) {
                return bad("random records must be at least 2 s long");
            }
        }
        TestKind::Sine | TestKind::Triangle => {
            let (Some(f), Some(a)) = (spec.frequency_hz, spec.amplitude_m) else {
                return bad("a sine or triangle test needs frequency_hz and amplitude_m");
            };
            if !(f.is_finite() && f > 0.0 && a.is_finite() && a > 0.0) {
                return bad("frequency_hz and amplitude_m must be finite and > 0");
            }
            if spec.kind == TestKind::Triangle && 1.0 / (4.0 * f) <= BLEND_S {
                return bad("triangle frequency too high for the 0.1 s reversal blend");
            }
        }
    }
    Ok(())
}

/// FFT bins `k` (frequency `k / d`) inside the band, without DC and Nyquist.
fn band_bins(lo: f64, hi: f64, d: f64, n: usize) -> (usize, usize) {
    let k_lo = ((lo * d - 1e-9).ceil().max(1.0)) as usize;
    let k_hi = ((hi * d + 1e-9).floor() as usize).min(n.saturating_sub(1) / 2);
    (k_lo, k_hi)
}

/// Raised-cosine fade `w(s)` for `s` seconds into a fade of length `tf`, and its first
/// two derivatives with respect to `s`.
#[inline]
fn fade(s: f64, tf: f64) -> (f64, f64, f64) {
    let c = PI / tf;
    let (sn, cs) = (c * s).sin_cos();
    (0.5 * (1.0 - cs), 0.5 * c * sn, 0.5 * c * c * cs)
}

/// Band-limited white-noise reference (see module doc). `stream` selects the test's
/// random phases; the continuous signal does not depend on `sample_rate_hz` (as long as
/// the band is below its Nyquist frequency), only its sampling does.
pub fn random_reference(
    spec: &TestSpec,
    seed: u64,
    stream: u64,
    random_duration_s: f64,
    sample_rate_hz: f64,
) -> Result<ReferenceSignal, SynthError> {
    check_spec(spec, random_duration_s, sample_rate_hz)?;
    let fs = sample_rate_hz;
    let (rms, [lo, hi]) = (spec.rms.unwrap_or(1.0), spec.band_hz.unwrap_or([0.0, 1.0]));
    let n_seg = (random_duration_s * fs).round() as usize;
    let d = n_seg as f64 / fs;
    let rest = (REST_S * fs).round() as usize;
    let (k_lo, k_hi) = band_bins(lo, hi, d, n_seg);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    // Spectra of displacement, velocity and acceleration over the segment's bins.
    let nb = n_seg / 2 + 1;
    let mut spec_x = vec![Complex::new(0.0, 0.0); nb];
    let mut spec_v = spec_x.clone();
    let mut spec_a = spec_x.clone();
    for k in k_lo..=k_hi {
        let phi = rng.gen::<f64>() * 2.0 * PI;
        let e = Complex::new(phi.cos(), phi.sin());
        let w = 2.0 * PI * k as f64 / d;
        let iw = Complex::new(0.0, w);
        match spec.control {
            Control::Displacement => {
                spec_x[k] = e;
                spec_v[k] = e * iw;
                spec_a[k] = e * (-w * w);
            }
            Control::Acceleration => {
                spec_a[k] = e;
                spec_v[k] = e / iw;
                spec_x[k] = e / (-w * w);
            }
        }
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let c2r = planner.plan_fft_inverse(n_seg);
    let mut g = [vec![0.0; n_seg], vec![0.0; n_seg], vec![0.0; n_seg]];
    for (out, sp) in g.iter_mut().zip([&mut spec_x, &mut spec_v, &mut spec_a]) {
        // DC and Nyquist bins are zero, so the input is a valid real spectrum.
        c2r.process(sp, out).map_err(|e| SynthError::BadTest {
            name: spec.name.clone(),
            message: format!("inverse FFT: {e}"),
        })?;
    }
    let [g0, g1, g2] = g;
    let mut r = ReferenceSignal::zeros(n_seg + 2 * rest);
    let (mut sum2, mut count) = (0.0, 0usize);
    for n in 0..n_seg {
        let tau = n as f64 / fs;
        let (w, w1, w2) = if tau < FADE_S {
            fade(tau, FADE_S)
        } else if d - tau < FADE_S {
            let (w, w1, w2) = fade(d - tau, FADE_S);
            (w, -w1, w2)
        } else {
            (1.0, 0.0, 0.0)
        };
        // product rule: r = w g, r' = w' g + w g', r'' = w'' g + 2 w' g' + w g''
        let x = w * g0[n];
        let v = w1 * g0[n] + w * g1[n];
        let a = w2 * g0[n] + 2.0 * w1 * g1[n] + w * g2[n];
        r.displacement_m[rest + n] = x;
        r.velocity_m_s[rest + n] = v;
        r.acceleration_m_s2[rest + n] = a;
        if w == 1.0 {
            let c = match spec.control {
                Control::Displacement => x,
                Control::Acceleration => a,
            };
            sum2 += c * c;
            count += 1;
        }
    }
    let scale = rms / (sum2 / count.max(1) as f64).sqrt();
    for ch in [
        &mut r.displacement_m,
        &mut r.velocity_m_s,
        &mut r.acceleration_m_s2,
    ] {
        for x in ch.iter_mut() {
            *x *= scale;
        }
    }
    Ok(r)
}

/// Sine reference with half-period raised-cosine ramps (see module doc).
pub fn sine_reference(spec: &TestSpec, sample_rate_hz: f64) -> Result<ReferenceSignal, SynthError> {
    check_spec(spec, DEFAULT_RANDOM_DURATION_S, sample_rate_hz)?;
    let f = spec.frequency_hz.unwrap_or(1.0);
    let amp = spec.amplitude_m.unwrap_or(0.0);
    let period = 1.0 / f;
    let ramp = period / 2.0;
    let motion = (sine_cycles(f) + 1) as f64 * period;
    let n = test_samples(spec, 0.0, sample_rate_hz);
    let w = 2.0 * PI * f;
    let mut r = ReferenceSignal::zeros(n);
    for k in 0..n {
        let tau = k as f64 / sample_rate_hz - REST_S;
        if tau <= 0.0 || tau >= motion {
            continue;
        }
        let (e, e1, e2) = if tau < ramp {
            fade(tau, ramp)
        } else if motion - tau < ramp {
            let (e, e1, e2) = fade(motion - tau, ramp);
            (e, -e1, e2)
        } else {
            (1.0, 0.0, 0.0)
        };
        let (s, c) = (w * tau).sin_cos();
        r.displacement_m[k] = amp * e * s;
        r.velocity_m_s[k] = amp * (e1 * s + e * w * c);
        r.acceleration_m_s2[k] = amp * (e2 * s + 2.0 * e1 * w * c - e * w * w * s);
    }
    Ok(r)
}

/// Triangle reference with rounded reversals (see module doc).
pub fn triangle_reference(
    spec: &TestSpec,
    sample_rate_hz: f64,
) -> Result<ReferenceSignal, SynthError> {
    check_spec(spec, DEFAULT_RANDOM_DURATION_S, sample_rate_hz)?;
    let f = spec.frequency_hz.unwrap_or(1.0);
    let amp = spec.amplitude_m.unwrap_or(0.0);
    let period = 1.0 / f;
    let tb = BLEND_S;
    let v = amp / (period / 4.0 - tb * (0.5 - 1.0 / PI));
    // velocity steps (time, dV): start +V, reversals -2V, +2V, ..., stop -V
    let mut steps: Vec<(f64, f64)> = vec![(REST_S, v)];
    for j in 0..2 * TRIANGLE_CYCLES {
        let sign = if j % 2 == 0 { -2.0 } else { 2.0 };
        steps.push((REST_S + period / 4.0 + j as f64 * period / 2.0, sign * v));
    }
    let t_end = REST_S + TRIANGLE_CYCLES as f64 * period;
    steps.push((t_end, -v));
    let n = test_samples(spec, 0.0, sample_rate_hz);
    let mut r = ReferenceSignal::zeros(n);
    for k in 0..n {
        let t = k as f64 / sample_rate_hz;
        if t <= REST_S - tb / 2.0 || t >= t_end + tb / 2.0 {
            continue;
        }
        let (mut x, mut xd, mut xdd) = (0.0, 0.0, 0.0);
        for &(tk, dv) in &steps {
            let s = (t - tk) / tb;
            if s <= -0.5 {
                continue;
            }
            if s >= 0.5 {
                // full step: velocity dV, displacement dV (t - tk)
                x += dv * (t - tk);
                xd += dv;
            } else {
                let (sn, cs) = (PI * s).sin_cos();
                // S(s) = (1 + sin pi s)/2; integral from -1/2: (s + 1/2)/2 - cos(pi s)/(2 pi)
                x += dv * tb * ((s + 0.5) / 2.0 - cs / (2.0 * PI));
                xd += dv * 0.5 * (1.0 + sn);
                xdd += dv * 0.5 * PI * cs / tb;
            }
        }
        r.displacement_m[k] = x;
        r.velocity_m_s[k] = xd;
        r.acceleration_m_s2[k] = xdd;
    }
    Ok(r)
}

/// The reference of a test at `sample_rate_hz`; `index` is the test's index in its
/// program (it selects the random stream).
pub fn reference(
    spec: &TestSpec,
    index: usize,
    seed: u64,
    random_duration_s: f64,
    sample_rate_hz: f64,
) -> Result<ReferenceSignal, SynthError> {
    match spec.kind {
        TestKind::Random => random_reference(
            spec,
            seed,
            2 * index as u64,
            random_duration_s,
            sample_rate_hz,
        ),
        TestKind::Sine => sine_reference(spec, sample_rate_hz),
        TestKind::Triangle => triangle_reference(spec, sample_rate_hz),
        TestKind::Record => Err(SynthError::BadTest {
            name: spec.name.clone(),
            message: "a `record` test has no synthetic reference".into(),
        }),
    }
}

/// One synthesised test with what the file does not hold: the noise-free readings and
/// the noise samples (for tests of the synthesis itself; identification sees `record`).
#[derive(Debug, Clone)]
pub struct SynthTest {
    pub record: Record,
    /// Noise-free readings at every sample (`valve_command` is the one actually sent).
    pub truth: Vec<Outputs>,
    /// Feedback noise at every sample (inside the loop).
    pub noise: Vec<SensorNoise>,
    /// Spool measurement noise at every sample (not fed back).
    pub spool_noise: Vec<f64>,
}

/// Synthesise one test: reference, seeded in-loop noise, simulation, record.
/// `index` is the test's index in its program (it selects the random streams).
pub fn synthesise_test(
    params: &Params,
    spec: &TestSpec,
    index: usize,
    opts: &SynthOptions,
    sample_rate_hz: f64,
) -> Result<SynthTest, SynthError> {
    let fs = sample_rate_hz;
    let r = reference(spec, index, opts.seed, opts.random_duration_s, fs)?;
    let n = r.len();
    let inputs = r.inputs();
    // sensor noise: white, seeded per test, drawn in a fixed order per sample
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    rng.set_stream(2 * index as u64 + 1);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let nl = opts.noise;
    let mut noise = Vec::with_capacity(n);
    let mut spool_noise = Vec::with_capacity(n);
    for _ in 0..n {
        spool_noise.push(nl.spool * normal.sample(&mut rng));
        noise.push(SensorNoise {
            displacement_m: nl.displacement_m * normal.sample(&mut rng),
            acceleration_m_s2: nl.acceleration_m_s2 * normal.sample(&mut rng),
            force_n: nl.force_n * normal.sample(&mut rng),
        });
    }
    let mut p = *params;
    p.controller = spec.controller.apply(&params.controller);
    let model = Model::new(&p);
    let noise_arg = if nl.is_none() { None } else { Some(&noise[..]) };
    let run = simulate_run(&model, &inputs, fs, noise_arg, opts.max_substep_s);
    if let Some(stop) = run.stop {
        return Err(SynthError::BadTest {
            name: spec.name.clone(),
            message: stop.reason,
        });
    }
    let truth = run.outputs;
    let rec = Record {
        time_s: (0..n).map(|k| k as f64 / fs).collect(),
        ref_displacement_m: r.displacement_m,
        ref_velocity_m_s: r.velocity_m_s,
        ref_acceleration_m_s2: r.acceleration_m_s2,
        // the controller's own digital signal: no added noise
        valve_command: Some(truth.iter().map(|o| o.valve_command).collect()),
        // measured channels: the true reading plus the very noise the controller saw
        spool_position: Some(
            truth
                .iter()
                .zip(&spool_noise)
                .map(|(o, e)| o.spool_position + e)
                .collect(),
        ),
        displacement_m: Some(
            truth
                .iter()
                .zip(&noise)
                .map(|(o, e)| o.displacement_m + e.displacement_m)
                .collect(),
        ),
        acceleration_m_s2: Some(
            truth
                .iter()
                .zip(&noise)
                .map(|(o, e)| o.acceleration_m_s2 + e.acceleration_m_s2)
                .collect(),
        ),
        force_n: Some(
            truth
                .iter()
                .zip(&noise)
                .map(|(o, e)| o.actuator_force_n + e.force_n)
                .collect(),
        ),
        // Extra channels for users (plots, checks): noise-free truths. Identification
        // and diagnosis do not use them.
        extra: vec![
            (
                "velocity_m_s".to_string(),
                truth.iter().map(|o| o.velocity_m_s).collect(),
            ),
            (
                "pressure_a_pa".to_string(),
                truth.iter().map(|o| o.pressure_a_pa).collect(),
            ),
            (
                "pressure_b_pa".to_string(),
                truth.iter().map(|o| o.pressure_b_pa).collect(),
            ),
        ],
    };
    Ok(SynthTest {
        record: rec,
        truth,
        noise,
        spool_noise,
    })
}

/// Progress callback: `(samples done, samples in total)`, called from worker threads
/// after each test.
pub type Progress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// Synthesise any list of tests (`(index, spec)`: index selects the random streams) in
/// parallel, each at its own `sample_rate_hz` if it has one, else at [`SAMPLE_RATE_HZ`]
/// (the campaign's rate). The campaign's `[controller]` and geometry come from `params`.
pub fn synthesise_program(
    params: &Params,
    program: &[(usize, TestSpec)],
    opts: &SynthOptions,
    progress: Option<Progress>,
) -> Result<Campaign, SynthError> {
    let fs = SAMPLE_RATE_HZ;
    let rate = |s: &TestSpec| s.sample_rate_hz.unwrap_or(fs);
    for (_, s) in program {
        check_spec(s, opts.random_duration_s, rate(s))?;
    }
    let total: u64 = program
        .iter()
        .map(|(_, s)| test_samples(s, opts.random_duration_s, rate(s)) as u64)
        .sum();
    let done = AtomicU64::new(0);
    let records = program
        .par_iter()
        .map(|(i, s)| {
            let t = synthesise_test(params, s, *i, opts, rate(s))?;
            let d =
                done.fetch_add(t.record.len() as u64, Ordering::Relaxed) + t.record.len() as u64;
            if let Some(cb) = progress {
                cb(d, total);
            }
            Ok(t.record)
        })
        .collect::<Result<Vec<Record>, SynthError>>()?;
    let names: Vec<&str> = program.iter().map(|(_, s)| s.name.as_str()).collect();
    Ok(Campaign {
        dir: PathBuf::new(),
        info: CampaignInfo {
            name: format!(
                "Synthetic campaign ({}; seed {})",
                if names.len() == 18 && opts.tests.is_none() {
                    "paper program".to_string()
                } else {
                    names.join(" ")
                },
                opts.seed
            ),
            sample_rate_hz: fs,
            geometry: Geometry::from_params(params),
            controller: ControllerOverride::known(&params.controller),
            tests: program.iter().map(|(_, s)| s.clone()).collect(),
        },
        records,
    })
}

/// The paper's program (or the subset `opts.tests`) with `(index, spec)` pairs.
pub fn selected_program(opts: &SynthOptions) -> Vec<(usize, TestSpec)> {
    paper_program(opts.random_duration_s)
        .into_iter()
        .enumerate()
        .filter(|(_, s)| match &opts.tests {
            Some(names) => names.iter().any(|n| n == &s.name),
            None => true,
        })
        .collect()
}

/// Synthesise the paper's test program (or the subset `opts.tests`) in memory
/// (`dir` is empty; [`write_synthetic`] or [`synthesise_to_dir`] put it on disk).
///
/// # Panics
/// If `opts.validate()` fails (the command line validates first); use
/// [`synthesise_program`] for a `Result`. `params` must be valid.
pub fn synthesise(params: &Params, opts: &SynthOptions, progress: Option<Progress>) -> Campaign {
    if let Err(e) = opts.validate() {
        panic!("invalid synthesis options: {e}");
    }
    synthesise_program(params, &selected_program(opts), opts, progress)
        .unwrap_or_else(|e| panic!("paper program: {e}"))
}

/// What `synthesis.toml` holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SynthesisInfo {
    pub generator: String,
    pub sample_rate_hz: f64,
    pub tests: Vec<String>,
    pub options: SynthOptions,
}

/// Write a synthesised campaign into `dir`: campaign.toml and the CSVs, plus
/// [`TRUTH_FILE`] (the full parameters used) and [`SYNTHESIS_FILE`] (seed, noise
/// levels, options). Identification must never read the last two.
pub fn write_synthetic(
    campaign: &Campaign,
    params: &Params,
    opts: &SynthOptions,
    dir: &Path,
) -> Result<(), CampaignError> {
    write_campaign(campaign, dir)?;
    let truth = dir.join(TRUTH_FILE);
    let text = format!(
        "# The parameters this synthetic campaign was made with (the truth).\n\
         # Tests may compare identified values with it; identification must never read it.\n{}",
        params.to_toml_string()
    );
    atomic_write(&truth, text.as_bytes())?;
    let info = SynthesisInfo {
        generator: format!("shaketable {} campaign synth", env!("CARGO_PKG_VERSION")),
        sample_rate_hz: campaign.info.sample_rate_hz,
        tests: campaign.info.tests.iter().map(|t| t.name.clone()).collect(),
        options: opts.clone(),
    };
    let syn = dir.join(SYNTHESIS_FILE);
    let text = format!(
        "# How this synthetic campaign was made (seed, sensor noise RMS, options).\n{}",
        toml::to_string(&info).map_err(|e| CampaignError::Invalid {
            file: syn.display().to_string(),
            message: e.to_string(),
        })?
    );
    atomic_write(&syn, text.as_bytes())?;
    Ok(())
}

/// Synthesise and write in one go; returns the campaign (with `dir` set).
pub fn synthesise_to_dir(
    params: &Params,
    opts: &SynthOptions,
    dir: &Path,
    progress: Option<Progress>,
) -> Result<Campaign, SynthError> {
    opts.validate()?;
    let mut c = synthesise_program(params, &selected_program(opts), opts, progress)?;
    write_synthetic(&c, params, opts, dir)?;
    c.dir = dir.to_path_buf();
    Ok(c)
}
