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
//!
//! Here: the options and the program; `reference.rs`: the reference signals; `run.rs`:
//! simulating a test or a program; `files.rs`: a synthesised campaign on disk.

mod files;
mod reference;
mod run;

pub use files::*;
pub use reference::*;
pub use run::*;

use super::format::CampaignError;
use super::{Control, TestKind, TestSpec};
use crate::solver::DEFAULT_MAX_SUBSTEP_S;
use serde::{Deserialize, Serialize};

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
