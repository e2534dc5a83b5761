//! Measured data: the campaign format of `shared/spec/campaign-format.md`.
//!
//! `types` (this file) holds the in-memory campaign; `format` reads and writes it on
//! disk with every bad-input rule of the format page; `synth` writes the paper's test
//! program from any parameter set with seeded in-loop sensor noise.

pub mod channel_names;
pub mod files;
pub mod format;
pub mod init;
pub mod matlab;
pub mod provenance;
mod rest;
pub mod reversals;
pub mod screen;
pub mod synth;

use crate::model::{Inputs, Reference};
use crate::params::{Controller, Params};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Manufacturer geometry known to the lab (`[geometry]` of campaign.toml): each key is
/// `None` when nobody wrote it down (campaign-format.md: a missing key is *unknown*).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    pub piston_area_m2: Option<f64>,
    pub total_oil_volume_m3: Option<f64>,
    pub supply_pressure_pa: Option<f64>,
    pub flow_gain_m3_s: Option<f64>,
}

impl Geometry {
    /// Every key known, from a parameter set.
    pub fn from_params(p: &Params) -> Geometry {
        Geometry {
            piston_area_m2: Some(p.actuator.piston_area_m2),
            total_oil_volume_m3: Some(p.actuator.total_oil_volume_m3),
            supply_pressure_pa: Some(p.actuator.supply_pressure_pa),
            flow_gain_m3_s: Some(p.actuator.flow_gain_m3_s),
        }
    }

    /// Each key with its parameter-file key and value.
    fn entries(&self) -> [(&'static str, Option<f64>); 4] {
        [
            ("actuator.piston_area_m2", self.piston_area_m2),
            ("actuator.total_oil_volume_m3", self.total_oil_volume_m3),
            ("actuator.supply_pressure_pa", self.supply_pressure_pa),
            ("actuator.flow_gain_m3_s", self.flow_gain_m3_s),
        ]
    }

    /// Put the known keys into `p`'s actuator block (the inverse of
    /// [`Self::from_params`]); returns the parameter-file keys left as they were.
    pub fn apply_to(&self, p: &mut Params) -> Vec<&'static str> {
        let a = &mut p.actuator;
        let targets = [
            &mut a.piston_area_m2,
            &mut a.total_oil_volume_m3,
            &mut a.supply_pressure_pa,
            &mut a.flow_gain_m3_s,
        ];
        let mut unknown = Vec::new();
        for ((key, value), target) in self.entries().into_iter().zip(targets) {
            match value {
                Some(v) => *target = v,
                None => unknown.push(key),
            }
        }
        unknown
    }
}

/// Controller gains a campaign does not give (campaign-format.md: unknown keys).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("controller gain{} {} of test `{test}` unknown: give {} in campaign.toml's [controller] (or the test's `controller = {{ ... }}`) to simulate it", if .gains.len() > 1 { "s" } else { "" }, .gains.join(", "), if .gains.len() > 1 { "them" } else { "it" })]
pub struct UnknownGains {
    pub test: String,
    pub gains: Vec<&'static str>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TestKind {
    Random,
    Sine,
    Triangle,
    /// Any other reference (earthquake, chirp, recorded drive): campaign-format.md's
    /// `record` kind; it needs neither a level nor a frequency.
    Record,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Control {
    Displacement,
    Acceleration,
}

/// Controller gains, each given or not: the campaign's `[controller]` (a gain nobody
/// wrote down is unknown) and a test's override (`controller = { fv = 0.0 }`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ControllerOverride {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kp: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kv: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ka: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fv: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fa: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kdp: Option<f64>,
}

impl ControllerOverride {
    /// Every gain known, from a parameter set.
    pub fn known(c: &Controller) -> ControllerOverride {
        ControllerOverride {
            kp: Some(c.kp),
            kv: Some(c.kv),
            ka: Some(c.ka),
            fv: Some(c.fv),
            fa: Some(c.fa),
            kdp: Some(c.kdp),
        }
    }

    /// These gains over `base` (each given here wins).
    pub fn over(&self, base: &ControllerOverride) -> ControllerOverride {
        ControllerOverride {
            kp: self.kp.or(base.kp),
            kv: self.kv.or(base.kv),
            ka: self.ka.or(base.ka),
            fv: self.fv.or(base.fv),
            fa: self.fa.or(base.fa),
            kdp: self.kdp.or(base.kdp),
        }
    }

    /// The parameter-file key of gain `gain` (`kp` -> `controller.kp`).
    pub fn parameter_key(gain: &str) -> &'static str {
        match gain {
            "kp" => "controller.kp",
            "kv" => "controller.kv",
            "ka" => "controller.ka",
            "fv" => "controller.fv",
            "fa" => "controller.fa",
            _ => "controller.kdp",
        }
    }

    /// The gains, if every one is known; else the names of those that are not.
    pub fn complete(&self) -> Result<Controller, Vec<&'static str>> {
        let named = [
            ("kp", self.kp),
            ("kv", self.kv),
            ("ka", self.ka),
            ("fv", self.fv),
            ("fa", self.fa),
            ("kdp", self.kdp),
        ];
        let unknown: Vec<&'static str> = named
            .iter()
            .filter(|(_, v)| v.is_none())
            .map(|(k, _)| *k)
            .collect();
        if !unknown.is_empty() {
            return Err(unknown);
        }
        let g = |x: Option<f64>| x.unwrap_or_default();
        Ok(Controller {
            kp: g(self.kp),
            kv: g(self.kv),
            ka: g(self.ka),
            fv: g(self.fv),
            fa: g(self.fa),
            kdp: g(self.kdp),
        })
    }

    /// The campaign gains with this test's overrides applied.
    pub fn apply(&self, base: &Controller) -> Controller {
        Controller {
            kp: self.kp.unwrap_or(base.kp),
            kv: self.kv.unwrap_or(base.kv),
            ka: self.ka.unwrap_or(base.ka),
            fv: self.fv.unwrap_or(base.fv),
            fa: self.fa.unwrap_or(base.fa),
            kdp: self.kdp.unwrap_or(base.kdp),
        }
    }
}

/// One `[[test]]` entry of campaign.toml.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TestSpec {
    pub name: String,
    pub file: String,
    pub kind: TestKind,
    pub control: Control,
    /// Random tests: RMS level (m for displacement control, m/s^2 for acceleration).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms: Option<f64>,
    /// Random tests: band `[low, high]`, Hz.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band_hz: Option<[f64; 2]>,
    /// Sine/triangle tests: frequency, Hz.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frequency_hz: Option<f64>,
    /// Sine/triangle tests: displacement amplitude, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude_m: Option<f64>,
    #[serde(default, skip_serializing_if = "is_default_override")]
    pub controller: ControllerOverride,
    /// The test's own sample rate, Hz, when campaign.toml gives one (campaign-format.md,
    /// "campaign.toml additions": `sample_rate_hz` is the default for every test; a test
    /// may set its own). `None`: the campaign's; read it with
    /// [`CampaignInfo::sample_rate_for`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample_rate_hz: Option<f64>,
}

impl TestSpec {
    /// Test `name` of `kind` under `control`, read from `file`, with no level, band,
    /// frequency, amplitude, gains or rate of its own (set those its kind needs).
    pub fn new(
        name: impl Into<String>,
        file: impl Into<String>,
        kind: TestKind,
        control: Control,
    ) -> TestSpec {
        TestSpec {
            name: name.into(),
            file: file.into(),
            kind,
            control,
            rms: None,
            band_hz: None,
            frequency_hz: None,
            amplitude_m: None,
            controller: ControllerOverride::default(),
            sample_rate_hz: None,
        }
    }

    /// A `record` test in displacement control (any recorded reference: it needs neither
    /// a level nor a frequency).
    pub fn record(name: impl Into<String>, file: impl Into<String>) -> TestSpec {
        TestSpec::new(name, file, TestKind::Record, Control::Displacement)
    }

    /// A random test of RMS level `rms` (m or m/s^2 as `control` says) over `band_hz`.
    pub fn random(
        name: impl Into<String>,
        file: impl Into<String>,
        control: Control,
        rms: f64,
        band_hz: [f64; 2],
    ) -> TestSpec {
        TestSpec {
            rms: Some(rms),
            band_hz: Some(band_hz),
            ..TestSpec::new(name, file, TestKind::Random, control)
        }
    }

    /// A periodic test (`kind` [`TestKind::Sine`] or [`TestKind::Triangle`]) in
    /// displacement control at `frequency_hz` with displacement amplitude `amplitude_m`.
    pub fn periodic(
        name: impl Into<String>,
        file: impl Into<String>,
        kind: TestKind,
        frequency_hz: f64,
        amplitude_m: f64,
    ) -> TestSpec {
        TestSpec {
            frequency_hz: Some(frequency_hz),
            amplitude_m: Some(amplitude_m),
            ..TestSpec::new(name, file, kind, Control::Displacement)
        }
    }
}

fn is_default_override(o: &ControllerOverride) -> bool {
    *o == ControllerOverride::default()
}

/// campaign.toml in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignInfo {
    pub name: String,
    /// The default rate of every test, Hz; a test may have its own
    /// ([`TestSpec::sample_rate_hz`], read with [`Self::sample_rate_for`]).
    pub sample_rate_hz: f64,
    pub geometry: Geometry,
    /// The gains campaign.toml gives (each may be unknown).
    pub controller: ControllerOverride,
    pub tests: Vec<TestSpec>,
}

impl CampaignInfo {
    /// The sample rate of test `spec`, Hz: its own, else the campaign's
    /// (campaign-format.md, "campaign.toml additions").
    pub fn sample_rate_for(&self, spec: &TestSpec) -> f64 {
        spec.sample_rate_hz.unwrap_or(self.sample_rate_hz)
    }

    /// Put the geometry and the campaign-wide gains campaign.toml gives into `p` (the
    /// gains only when every one is given); returns the parameter-file keys nobody wrote
    /// down (campaign-format.md: a missing key is *unknown*), which `p` keeps as they were.
    pub fn apply_known(&self, p: &mut Params) -> Vec<&'static str> {
        let mut unknown = self.geometry.apply_to(p);
        match self.controller.complete() {
            Ok(k) => p.controller = k,
            Err(gains) => {
                unknown.extend(gains.iter().map(|k| ControllerOverride::parameter_key(k)))
            }
        }
        unknown
    }
}

/// One recorded test: the channels of the CSV, SI units, uniform sampling.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Record {
    pub time_s: Vec<f64>,
    pub ref_displacement_m: Vec<f64>,
    pub ref_velocity_m_s: Vec<f64>,
    pub ref_acceleration_m_s2: Vec<f64>,
    pub valve_command: Option<Vec<f64>>,
    /// Absent in campaigns recorded without the spool LVDT.
    pub spool_position: Option<Vec<f64>>,
    pub displacement_m: Option<Vec<f64>>,
    pub acceleration_m_s2: Option<Vec<f64>>,
    pub force_n: Option<Vec<f64>>,
    /// Further channels (`velocity_m_s`, `pressure_a_pa`, ...), kept in file order.
    pub extra: Vec<(String, Vec<f64>)>,
}

/// A measured channel a laboratory's test may lack (campaign-format.md, "What is required,
/// what is optional": a test needs the displacement or the acceleration; the valve
/// command, spool and force are optional).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measured {
    ValveCommand,
    Spool,
    Displacement,
    Acceleration,
    Force,
}

impl Measured {
    /// The channel's name in the campaign format.
    pub fn name(self) -> &'static str {
        match self {
            Measured::ValveCommand => "valve_command",
            Measured::Spool => format::SPOOL_CHANNEL,
            Measured::Displacement => "displacement_m",
            Measured::Acceleration => "acceleration_m_s2",
            Measured::Force => "force_n",
        }
    }
}

impl Record {
    /// The measured channel `m`, `None` when the test did not record it.
    pub fn measured(&self, m: Measured) -> Option<&[f64]> {
        match m {
            Measured::ValveCommand => self.valve_command.as_deref(),
            Measured::Spool => self.spool_position.as_deref(),
            Measured::Displacement => self.displacement_m.as_deref(),
            Measured::Acceleration => self.acceleration_m_s2.as_deref(),
            Measured::Force => self.force_n.as_deref(),
        }
    }

    /// Whether the test recorded every channel of `needs`.
    pub fn has_all(&self, needs: &[Measured]) -> bool {
        needs.iter().all(|&m| self.measured(m).is_some())
    }

    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// Every channel the record holds, by its campaign-format name, in the format's order
    /// (time, the references, the measured channels, then the further channels).
    pub fn channels(&self) -> Vec<(&str, &[f64])> {
        let mut v: Vec<(&str, &[f64])> = vec![
            ("time_s", &self.time_s),
            ("ref_displacement_m", &self.ref_displacement_m),
            ("ref_velocity_m_s", &self.ref_velocity_m_s),
            ("ref_acceleration_m_s2", &self.ref_acceleration_m_s2),
        ];
        let measured = [
            Measured::ValveCommand,
            Measured::Spool,
            Measured::Displacement,
            Measured::Acceleration,
            Measured::Force,
        ];
        v.extend(
            measured
                .into_iter()
                .filter_map(|m| self.measured(m).map(|x| (m.name(), x))),
        );
        v.extend(self.extra.iter().map(|(n, x)| (n.as_str(), x.as_slice())));
        v
    }

    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// The controller inputs at every sample (external force zero).
    pub fn inputs(&self) -> Vec<Inputs> {
        (0..self.len())
            .map(|k| Inputs {
                reference: Reference {
                    displacement_m: self.ref_displacement_m[k],
                    velocity_m_s: self.ref_velocity_m_s[k],
                    acceleration_m_s2: self.ref_acceleration_m_s2[k],
                },
                external_force_n: 0.0,
            })
            .collect()
    }
}

/// A campaign: where it lives, what campaign.toml says, and each test's record
/// (in the order of the `[[test]]` list).
#[derive(Debug, Clone, PartialEq)]
pub struct Campaign {
    pub dir: PathBuf,
    pub info: CampaignInfo,
    pub records: Vec<Record>,
    /// How each test's file was read, by test name (column, scale and offset of every
    /// channel; [`provenance`]); empty for a campaign made in memory (synthesised).
    pub sources: provenance::SourcesByTest,
}

impl Campaign {
    /// The test spec and record named `name` (e.g. "R2"), if the campaign has it.
    pub fn test(&self, name: &str) -> Option<(&TestSpec, &Record)> {
        self.info
            .tests
            .iter()
            .position(|t| t.name == name)
            .map(|i| (&self.info.tests[i], &self.records[i]))
    }

    /// The sample rate of test `spec`, Hz ([`CampaignInfo::sample_rate_for`]).
    pub fn sample_rate_for(&self, spec: &TestSpec) -> f64 {
        self.info.sample_rate_for(spec)
    }

    /// Whether `channel` of test `test` was computed here from the recorded reference (its
    /// derivative or integral, [`provenance::Source::Computed`]) rather than read.
    pub fn computed_here(&self, test: &str, channel: &str) -> bool {
        self.sources
            .get(test)
            .and_then(|s| s.of(channel))
            .is_some_and(|s| matches!(s, provenance::Source::Computed { .. }))
    }

    /// The sample rate of the `i`-th test (and record), Hz; the campaign's when `i` is
    /// out of range.
    pub fn sample_rate_of(&self, i: usize) -> f64 {
        self.info
            .tests
            .get(i)
            .map_or(self.info.sample_rate_hz, |t| self.sample_rate_for(t))
    }

    /// The controller gains in force during test `spec`, or the gains nobody gave.
    pub fn controller_for(&self, spec: &TestSpec) -> Result<Controller, UnknownGains> {
        spec.controller
            .over(&self.info.controller)
            .complete()
            .map_err(|gains| UnknownGains {
                test: spec.name.clone(),
                gains,
            })
    }

    /// The campaign as a laboratory often has it: only the reference and the table's
    /// motion recorded (no valve command, spool or force), no gains and no geometry
    /// written down. For tests and benchmarks of identification from such recordings.
    pub fn as_motion_only(mut self) -> Campaign {
        self.info.controller = ControllerOverride::default();
        self.info.geometry = Geometry::default();
        for r in &mut self.records {
            r.valve_command = None;
            r.spool_position = None;
            r.force_n = None;
        }
        self
    }

    /// Every test's gains are known (what simulating the campaign needs).
    pub fn gains_known(&self) -> Result<(), UnknownGains> {
        self.info
            .tests
            .iter()
            .try_for_each(|t| self.controller_for(t).map(|_| ()))
    }
}

/// Least-squares line `(intercept, slope)` of `y` against `t` (a flat line through the mean
/// when `t` does not vary). The rest segments of a reference integrated to rest
/// (`format/integrate.rs`) and the free play's levelling before a reversal
/// (`diagnose/free_play_start.rs`) both fit it.
pub(crate) fn line_fit(t: &[f64], y: &[f64]) -> (f64, f64) {
    let n = t.len() as f64;
    let (mt, my) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sty, mut stt) = (0.0, 0.0);
    for (t, y) in t.iter().zip(y) {
        sty += (t - mt) * (y - my);
        stt += (t - mt) * (t - mt);
    }
    let s = if stt > 0.0 { sty / stt } else { 0.0 };
    (my - s * mt, s)
}

/// The smallest and largest sample of `x`, NaN ignored; (inf, -inf) when there is none
/// (screening's flat-channel check and the what-was-read table both read it).
pub(crate) fn min_max(x: &[f64]) -> (f64, f64) {
    x.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        })
}
