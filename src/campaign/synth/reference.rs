//! The reference signals of the paper's test kinds (r, r', r'' exactly consistent): band-
//! limited random noise, ramped sines and smoothed triangles (see the module doc of
//! [`super`]).

use super::*;
use crate::campaign::{Control, TestKind, TestSpec};
use crate::model::{Inputs, Reference};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use std::f64::consts::PI;

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

pub(super) fn check_spec(
    spec: &TestSpec,
    random_duration_s: f64,
    fs: f64,
) -> Result<(), SynthError> {
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
    let seg = RandomSegment::new(lo, hi, random_duration_s, fs);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    let spectra = seg.spectra(spec.control, &mut rng);
    let g = inverse_ffts(spec, seg.n_seg, spectra)?;
    let (mut r, rms_unit) = seg.faded(spec.control, fs, g);
    let scale = rms / rms_unit;
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

/// The band-limited part of a random reference: its samples and length, the rest
/// before and after it, and its FFT bins inside the band.
struct RandomSegment {
    n_seg: usize,
    /// The segment's length, s: bin `k` is at frequency `k / d`.
    d: f64,
    /// Samples at rest before and after the segment.
    rest: usize,
    k_lo: usize,
    k_hi: usize,
}

impl RandomSegment {
    /// The segment of `random_duration_s` at `fs` for the band `[lo, hi]` Hz.
    fn new(lo: f64, hi: f64, random_duration_s: f64, fs: f64) -> Self {
        let n_seg = (random_duration_s * fs).round() as usize;
        let d = n_seg as f64 / fs;
        let rest = (REST_S * fs).round() as usize;
        let (k_lo, k_hi) = band_bins(lo, hi, d, n_seg);
        RandomSegment {
            n_seg,
            d,
            rest,
            k_lo,
            k_hi,
        }
    }

    /// Spectra of displacement, velocity and acceleration over the segment's bins: one
    /// random phase per bin of the band, drawn from `rng` in bin order; the controlled
    /// channel has unit amplitude, the others follow by `i w`.
    fn spectra(&self, control: Control, rng: &mut ChaCha8Rng) -> [Vec<Complex<f64>>; 3] {
        let nb = self.n_seg / 2 + 1;
        let mut spec_x = vec![Complex::new(0.0, 0.0); nb];
        let mut spec_v = spec_x.clone();
        let mut spec_a = spec_x.clone();
        for k in self.k_lo..=self.k_hi {
            let phi = rng.gen::<f64>() * 2.0 * PI;
            let e = Complex::new(phi.cos(), phi.sin());
            let w = 2.0 * PI * k as f64 / self.d;
            let iw = Complex::new(0.0, w);
            match control {
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
        [spec_x, spec_v, spec_a]
    }

    /// The reference: the rest, the signals `g = [g, g', g'']` under the fade window
    /// (product rule), the rest again; and the RMS of the controlled channel where the
    /// window is 1 (to scale it to the test's rms).
    fn faded(&self, control: Control, fs: f64, g: [Vec<f64>; 3]) -> (ReferenceSignal, f64) {
        let [g0, g1, g2] = g;
        let rest = self.rest;
        let mut r = ReferenceSignal::zeros(self.n_seg + 2 * rest);
        let (mut sum2, mut count) = (0.0, 0usize);
        for n in 0..self.n_seg {
            let tau = n as f64 / fs;
            let (w, w1, w2) = fade_in_out(tau, self.d, FADE_S);
            // product rule: r = w g, r' = w' g + w g', r'' = w'' g + 2 w' g' + w g''
            let x = w * g0[n];
            let v = w1 * g0[n] + w * g1[n];
            let a = w2 * g0[n] + 2.0 * w1 * g1[n] + w * g2[n];
            r.displacement_m[rest + n] = x;
            r.velocity_m_s[rest + n] = v;
            r.acceleration_m_s2[rest + n] = a;
            if w == 1.0 {
                let c = match control {
                    Control::Displacement => x,
                    Control::Acceleration => a,
                };
                sum2 += c * c;
                count += 1;
            }
        }
        (r, (sum2 / count.max(1) as f64).sqrt())
    }
}

/// The real signals of the three spectra, each by an inverse FFT of length `n_seg`.
fn inverse_ffts(
    spec: &TestSpec,
    n_seg: usize,
    mut spectra: [Vec<Complex<f64>>; 3],
) -> Result<[Vec<f64>; 3], SynthError> {
    let mut planner = RealFftPlanner::<f64>::new();
    let c2r = planner.plan_fft_inverse(n_seg);
    let mut g = [vec![0.0; n_seg], vec![0.0; n_seg], vec![0.0; n_seg]];
    for (out, sp) in g.iter_mut().zip(spectra.iter_mut()) {
        // DC and Nyquist bins are zero, so the input is a valid real spectrum.
        c2r.process(sp, out).map_err(|e| SynthError::BadTest {
            name: spec.name.clone(),
            message: format!("inverse FFT: {e}"),
        })?;
    }
    Ok(g)
}

/// The window at `tau` seconds into a motion of `length` s that fades in over its first
/// `tf` s and out over its last `tf` s (1 between), and its first two derivatives.
fn fade_in_out(tau: f64, length: f64, tf: f64) -> (f64, f64, f64) {
    if tau < tf {
        fade(tau, tf)
    } else if length - tau < tf {
        let (w, w1, w2) = fade(length - tau, tf);
        (w, -w1, w2)
    } else {
        (1.0, 0.0, 0.0)
    }
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
        let (e, e1, e2) = fade_in_out(tau, motion, ramp);
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
