//! What was read (issue 16, part 7): where each channel of each test came from (a
//! column of the file with its scale and offset, a reference computed from the one that
//! was recorded, a time base made from the sample rate), and the summary of a campaign
//! as read ([`CampaignRead`]): per test its file, kind, rate, samples and duration, and
//! per channel its SI unit, its source and its range; the geometry and gains nobody wrote
//! down. `campaign check`, `identify` (JSON `read`) and the report show it.

use super::{Campaign, Control, Record, TestKind};
use crate::params::Params;
use serde::Serialize;
use std::collections::BTreeMap;

/// Where a channel's samples came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "from", rename_all = "snake_case")]
pub enum Source {
    /// A column (a MATLAB variable or signal) of the test's file:
    /// `value = scale * (raw - offset)` (campaign-format.md, `[columns]`).
    Column {
        column: String,
        scale: f64,
        offset: f64,
    },
    /// Computed in the frequency domain from the recorded reference `channel`: its
    /// derivative of `order` (a negative order is an integral, corrected to rest where
    /// the record starts and ends at rest).
    Computed { channel: &'static str, order: i32 },
    /// The time base made from the sample rate (no time column mapped).
    SampleRate { sample_rate_hz: f64 },
    /// The campaign was made in memory (synthesised): no file was read.
    InMemory,
}

impl Source {
    /// A column read as it is (the project's own form, or an unmapped column).
    pub fn same_column(name: &str) -> Source {
        Source::Column {
            column: name.to_string(),
            scale: 1.0,
            offset: 0.0,
        }
    }

    /// The reference channel `channel` computed from the recorded one of a test under
    /// `control` (campaign-format.md: the missing reference derivatives are computed).
    pub fn computed_reference(control: Control, channel: &str) -> Source {
        let (from, order) = match (control, channel) {
            (Control::Displacement, "ref_velocity_m_s") => ("ref_displacement_m", 1),
            (Control::Displacement, _) => ("ref_displacement_m", 2),
            (Control::Acceleration, "ref_velocity_m_s") => ("ref_acceleration_m_s2", -1),
            (Control::Acceleration, _) => ("ref_acceleration_m_s2", -2),
        };
        Source::Computed {
            channel: from,
            order,
        }
    }
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Source::Column {
                column,
                scale,
                offset,
            } => match (*scale == 1.0, *offset == 0.0) {
                (true, true) => write!(f, "`{column}`"),
                (false, true) => write!(f, "{scale} x `{column}`"),
                (true, false) => write!(f, "`{column}` - {offset}"),
                (false, false) => write!(f, "{scale} x (`{column}` - {offset})"),
            },
            Source::Computed { channel, order } => {
                let what = match order {
                    1 => "derivative",
                    2 => "second derivative",
                    -1 => "integral",
                    _ => "double integral",
                };
                write!(f, "{what} of {channel} (frequency domain)")
            }
            Source::SampleRate { sample_rate_hz } => {
                write!(f, "k / {sample_rate_hz} Hz (no time column)")
            }
            Source::InMemory => write!(f, "made in memory (no file read)"),
        }
    }
}

/// One channel of a test and where it came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelSource {
    pub channel: String,
    pub source: Source,
}

/// How one test's file was read: every channel's source, and the file's columns that
/// were not read (text nobody mapped: a date, an event note).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Sources {
    pub channels: Vec<ChannelSource>,
    pub unread_columns: Vec<String>,
}

impl Sources {
    /// Every channel of `r` read from the column of its own name (the project's form).
    pub fn same_columns(r: &Record) -> Sources {
        Sources {
            channels: r
                .channels()
                .into_iter()
                .map(|(name, _)| ChannelSource {
                    channel: name.to_string(),
                    source: Source::same_column(name),
                })
                .collect(),
            unread_columns: Vec::new(),
        }
    }

    /// The source of `channel`, if this file gave it.
    pub fn of(&self, channel: &str) -> Option<&Source> {
        self.channels
            .iter()
            .find(|c| c.channel == channel)
            .map(|c| &c.source)
    }
}

/// The sources of a campaign's tests, by test name.
pub type SourcesByTest = BTreeMap<String, Sources>;

/// The SI unit of a campaign-format channel (campaign-format.md, "The CSV records": the
/// unit is the name's suffix); `None` for a column kept under a name of its own (a DAQ's
/// sample number), whose unit is the file's.
pub fn unit_of(channel: &str) -> Option<&'static str> {
    /// Suffixes of the format's names and their units, longest first where one ends
    /// another (`_m_s2` before `_m_s`).
    const SUFFIX_UNITS: [(&str, &str); 7] = [
        ("_m_s2", "m/s^2"),
        ("_m_s", "m/s"),
        ("_m", "m"),
        ("_n", "N"),
        ("_pa", "Pa"),
        ("_s", "s"),
        ("_hz", "Hz"),
    ];
    match channel {
        "valve_command" | "spool_position" => Some("1 (normalised)"),
        _ => SUFFIX_UNITS
            .iter()
            .find(|(suffix, _)| channel.ends_with(suffix))
            .map(|(_, unit)| *unit),
    }
}

/// One channel as read.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelRead {
    pub channel: String,
    /// SI unit after mapping; `None`: a column kept as the file has it.
    pub unit: Option<&'static str>,
    pub source: Source,
    /// Smallest and largest sample, in the unit (a check of scale and sign).
    pub min: f64,
    pub max: f64,
}

/// One test as read.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TestRead {
    pub test: String,
    pub file: String,
    pub kind: TestKind,
    pub control: Control,
    pub sample_rate_hz: f64,
    /// The test gives its own `sample_rate_hz` (else the campaign's).
    pub own_rate: bool,
    pub samples: usize,
    /// `samples / sample_rate_hz`, s.
    pub duration_s: f64,
    pub channels: Vec<ChannelRead>,
    pub unread_columns: Vec<String>,
}

/// A campaign as read: every test (before screening) and the parameter-file keys of the
/// geometry and gains campaign.toml does not give.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CampaignRead {
    pub campaign: String,
    pub sample_rate_hz: f64,
    pub tests: Vec<TestRead>,
    pub unknown_keys: Vec<&'static str>,
}

impl Campaign {
    /// What was read: per test and channel, with the sources [`Campaign::sources`] holds.
    pub fn what_was_read(&self) -> CampaignRead {
        let tests = self
            .info
            .tests
            .iter()
            .zip(&self.records)
            .map(|(spec, r)| {
                let sources = self.sources.get(&spec.name);
                let fs = self.sample_rate_for(spec);
                let channels = r
                    .channels()
                    .into_iter()
                    .map(|(name, x)| {
                        let (min, max) = super::min_max(x);
                        ChannelRead {
                            channel: name.to_string(),
                            unit: unit_of(name),
                            source: sources
                                .and_then(|s| s.of(name))
                                .cloned()
                                .unwrap_or(Source::InMemory),
                            min,
                            max,
                        }
                    })
                    .collect();
                TestRead {
                    test: spec.name.clone(),
                    file: spec.file.clone(),
                    kind: spec.kind,
                    control: spec.control,
                    sample_rate_hz: fs,
                    own_rate: spec.sample_rate_hz.is_some(),
                    samples: r.len(),
                    duration_s: r.len() as f64 / fs,
                    channels,
                    unread_columns: sources
                        .map(|s| s.unread_columns.clone())
                        .unwrap_or_default(),
                }
            })
            .collect();
        CampaignRead {
            campaign: self.info.name.clone(),
            sample_rate_hz: self.info.sample_rate_hz,
            tests,
            unknown_keys: self.info.apply_known(&mut Params::trees_lab()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_follow_the_format_names() {
        assert_eq!(unit_of("ref_acceleration_m_s2"), Some("m/s^2"));
        assert_eq!(unit_of("ref_velocity_m_s"), Some("m/s"));
        assert_eq!(unit_of("displacement_m"), Some("m"));
        assert_eq!(unit_of("force_n"), Some("N"));
        assert_eq!(unit_of("pressure_a_pa"), Some("Pa"));
        assert_eq!(unit_of("time_s"), Some("s"));
        assert_eq!(unit_of("spool_position"), Some("1 (normalised)"));
        assert_eq!(unit_of("Sample Number"), None);
        assert_eq!(unit_of("displacement_mm"), None);
    }

    #[test]
    fn sources_say_how_the_value_was_made() {
        let s = Source::Column {
            column: "CHANNEL0".into(),
            scale: 0.01,
            offset: 0.0,
        };
        assert_eq!(s.to_string(), "0.01 x `CHANNEL0`");
        assert_eq!(
            Source::computed_reference(Control::Displacement, "ref_acceleration_m_s2").to_string(),
            "second derivative of ref_displacement_m (frequency domain)"
        );
        assert_eq!(
            Source::computed_reference(Control::Acceleration, "ref_velocity_m_s"),
            Source::Computed {
                channel: "ref_acceleration_m_s2",
                order: -1
            }
        );
    }
}
