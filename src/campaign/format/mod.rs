//! Reading and writing campaigns on disk (`shared/spec/campaign-format.md`).
//!
//! Every bad input is a [`CampaignError`] naming the file and the physical line (1-based,
//! comment and blank lines counted) and, for campaign.toml, the key and the test; never a
//! panic and never a silently wrong result. Floats are written with `ryu` (shortest
//! round-trip representation), so a record read back is bit-for-bit the record written.
//!
//! Choices where the format page is silent:
//! - campaign.toml: `name` may be omitted (the directory name is used); `sample_rate_hz`
//!   is the default of every test; a test may give its own, checked by the same rules and
//!   bounding that test's frequencies. In a laboratory's form a test with a mapped `time_s`
//!   column may have neither: it takes its time column's rate (plausible, 1 Hz to 1 MHz),
//!   which bounds its frequencies once read. Per test `name`, `file`, `kind`, `control`
//!   (+ `rms`, `band_hz` for random, `frequency_hz`, `amplitude_m` for sine/triangle) are
//!   required; `[geometry]` and `[controller]` keys are optional (unknown when missing).
//!   Unknown keys are accepted and ignored, except inside `[controller]` and a test's
//!   `controller = {...}` override, where an unknown gain (e.g. a typo `Fv`) would
//!   silently change the physics, so it is an error.
//! - Duplicate test names, two tests on one file, and a campaign without tests are errors.
//! - CSV: blank lines and lines whose first non-blank character is `#` are skipped;
//!   cells are trimmed and may be double-quoted; a duplicate channel name is an error.
//! - Time: strictly increasing; the rate of the time column's own uniform grid (a least
//!   squares fit, gaps counted as whole steps) must match `sample_rate_hz` within 0.1 %
//!   (else "sample rate disagrees"; a smaller offset is accepted, never accumulated into
//!   jitter), and every sample must lie within 1 % of a step of that grid (else
//!   "non-uniform time": gaps, jitter, drift). The record may start at any t0.
//! - Files (see [`super::files`]): only regular files inside the campaign folder, within
//!   [`MAX_RECORD_BYTES`] / [`MAX_TOML_BYTES`], UTF-8; lines end at LF, CRLF or a lone CR.
//! - campaign.toml values must lie in plausible physical ranges (named bounds below), and
//!   test files are compared after normalisation (`./R1.csv` is `R1.csv`; symlinks and
//!   hard links to one file are one file).

use super::files::{
    decode_utf8, lines_any, lone_cr_to_lf, normalise_relative, read_regular, resolve_inside,
    Refusal,
};
pub use super::files::{MAX_RECORD_BYTES, MAX_TOML_BYTES};
use super::provenance::Sources;
use super::{
    Campaign, CampaignInfo, Control, ControllerOverride, Geometry, Record, TestKind, TestSpec,
};
use crate::params::{self, Rule};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Channels every record must have (campaign-format.md, "The CSV records").
pub const REQUIRED_CHANNELS: [&str; 8] = [
    "time_s",
    "ref_displacement_m",
    "ref_velocity_m_s",
    "ref_acceleration_m_s2",
    "valve_command",
    "displacement_m",
    "acceleration_m_s2",
    "force_n",
];

/// Channels a reference-only file (input of `shaketable simulate`) must have.
pub const REFERENCE_CHANNELS: [&str; 4] = [
    "time_s",
    "ref_displacement_m",
    "ref_velocity_m_s",
    "ref_acceleration_m_s2",
];

/// The optional spool channel.
pub const SPOOL_CHANNEL: &str = "spool_position";

/// Relative tolerance of the time column's rate against `sample_rate_hz`: 0.1 %
/// (campaign-format.md, "a sample rate that disagrees with a time column by more than
/// 0.1 %"). A smaller offset is a clock tolerance and is accepted.
const RATE_TOLERANCE: f64 = 1e-3;
/// Tolerance of each sample time against the time column's own fitted uniform grid, in
/// sample intervals: jitter, gaps and drift beyond 1 % of a step are "non-uniform time".
const GRID_TOLERANCE: f64 = 1e-2;

/// Everything that can be wrong with a campaign on disk.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// A file that cannot be read (missing, unreadable, not UTF-8).
    #[error("{file}: cannot read: {source}")]
    Read {
        file: String,
        source: std::io::Error,
    },
    /// A file or directory that cannot be written.
    #[error("{file}: cannot write: {source}")]
    Write {
        file: String,
        source: std::io::Error,
    },
    /// Bad content of a CSV record: ragged row, non-numeric or non-finite cell, time
    /// column problems, missing channel, empty record.
    #[error("{file}: line {line}: {message}")]
    Csv {
        file: String,
        line: usize,
        message: String,
    },
    /// Bad content of campaign.toml: syntax, missing or invalid key, unknown kind, ...
    #[error("{file}: {}{message}", toml_context(*line, test, key))]
    Toml {
        file: String,
        /// The line of the offending value, or of the `[[test]]`/`[table]` header for a
        /// missing key; `None` only for a missing top-level key.
        line: Option<usize>,
        test: Option<String>,
        key: Option<String>,
        message: String,
    },
    /// A file refused before it is read: not a regular file (FIFO, device, directory,
    /// socket) or larger than any plausible one.
    #[error("{file}: {message}")]
    Refused { file: String, message: String },
    /// An in-memory record or campaign that cannot be written in the format.
    #[error("{file}: {message}")]
    Invalid { file: String, message: String },
    /// A MATLAB file that cannot be read, or a mapped variable or signal it lacks
    /// (the message names the file and the variable).
    #[error("{message}")]
    Matlab { file: String, message: String },
    /// An output refused or not written by the safe-write rules ([`crate::output`]).
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

fn toml_context(line: Option<usize>, test: &Option<String>, key: &Option<String>) -> String {
    let mut s = String::new();
    if let Some(l) = line {
        s.push_str(&format!("line {l}: "));
    }
    if let Some(t) = test {
        s.push_str(&format!("test `{t}`: "));
    }
    if let Some(k) = key {
        s.push_str(&format!("key `{k}`: "));
    }
    s
}

impl CampaignError {
    /// The line the error points at, if it has one.
    pub fn line(&self) -> Option<usize> {
        match self {
            CampaignError::Csv { line, .. } => Some(*line),
            CampaignError::Toml { line, .. } => *line,
            _ => None,
        }
    }

    /// The file the error is about.
    pub fn file(&self) -> &str {
        match self {
            CampaignError::Read { file, .. }
            | CampaignError::Write { file, .. }
            | CampaignError::Csv { file, .. }
            | CampaignError::Toml { file, .. }
            | CampaignError::Refused { file, .. }
            | CampaignError::Invalid { file, .. }
            | CampaignError::Matlab { file, .. } => file,
            CampaignError::Output(e) => e.path(),
        }
    }
}

fn display(p: &Path) -> String {
    p.display().to_string()
}

/// A record or campaign.toml as text: a regular file within its size bound, UTF-8 (an
/// invalid byte is an error at its line and column).
fn read_text(path: &Path, toml: bool) -> Result<String, CampaignError> {
    let file = display(path);
    let (limit, what) = if toml {
        (MAX_TOML_BYTES, "largest plausible campaign.toml")
    } else {
        (MAX_RECORD_BYTES, "largest plausible record")
    };
    let bytes = read_regular(path, limit, what).map_err(|r| refusal(&file, r))?;
    decode_utf8(bytes).map_err(|b| {
        if toml {
            CampaignError::Toml {
                file,
                line: Some(b.line),
                test: None,
                key: None,
                message: b.to_string(),
            }
        } else {
            CampaignError::Csv {
                file,
                line: b.line,
                message: b.to_string(),
            }
        }
    })
}

/// A file refused by [`read_regular`], as the error naming it.
fn refusal(file: &str, r: Refusal) -> CampaignError {
    match r {
        Refusal::Io(source) => CampaignError::Read {
            file: file.to_string(),
            source,
        },
        other => CampaignError::Refused {
            file: file.to_string(),
            message: other.to_string(),
        },
    }
}

mod csv;
mod integrate;
pub mod layout;
mod open;
mod toml_file;
mod toml_gains;
mod toml_layout;
mod toml_test;
mod toml_values;
mod write;

use csv::*;

use layout::merge_columns;
pub use layout::{ColumnEntry, ColumnMap, Decimal, Delimiter, ReadOptions, ReadOverride, ReadPlan};
pub use open::{read_campaign, read_campaign_info, read_campaign_test};
pub use toml_file::{parse_campaign_toml, parse_campaign_toml_planned};
pub use write::*;

/// Read one record, checking every rule of the format page against `sample_rate_hz`.
pub fn read_record(path: &Path, sample_rate_hz: f64) -> Result<Record, CampaignError> {
    let file = display(path);
    let text = read_text(path, false)?;
    read_record_str(&text, &file, sample_rate_hz, "sample_rate_hz")
}

/// [`read_record`] on text already in memory; `file` names it in errors and
/// `rate_source` says where the sample rate came from (e.g. "campaign.toml sample_rate_hz").
pub fn read_record_str(
    text: &str,
    file: &str,
    sample_rate_hz: f64,
    rate_source: &str,
) -> Result<Record, CampaignError> {
    read_project_form(text, file, Some(sample_rate_hz), rate_source).map(|(r, _)| r)
}

/// A record in the project's own form and its rate: `sample_rate_hz`, checked against the
/// time column, or (`None`) the time column's.
fn read_project_form(
    text: &str,
    file: &str,
    sample_rate_hz: Option<f64>,
    rate_source: &str,
) -> Result<(Record, f64), CampaignError> {
    let table = parse_csv(text, file, &ReadOptions::default(), true)?;
    require_channels(&table, &REQUIRED_CHANNELS, file)?;
    let time = &table.columns[table.index("time_s").unwrap_or(0)];
    let fs = check_time(&table, time, sample_rate_hz, rate_source, file)?;
    Ok((record_from_table(table), fs))
}

/// One test's text read under its [`ReadPlan`]: the project's form as
/// [`read_record_str`], a laboratory's form mapped ([`layout`]); with where each channel
/// came from.
pub fn read_record_planned(
    text: &str,
    file: &str,
    plan: &ReadPlan,
    rate_source: &str,
) -> Result<(Record, Sources), CampaignError> {
    read_planned_rate(text, file, plan, rate_source).map(|(r, s, _)| (r, s))
}

/// [`read_record_planned`] with the record's rate (the plan's, else its time column's).
fn read_planned_rate(
    text: &str,
    file: &str,
    plan: &ReadPlan,
    rate_source: &str,
) -> Result<(Record, Sources, f64), CampaignError> {
    if !plan.lab_form {
        let (r, fs) = read_project_form(text, file, plan.sample_rate_hz, rate_source)?;
        let sources = Sources::same_columns(&r);
        return Ok((r, sources, fs));
    }
    let table = parse_csv(text, file, &plan.read, false)?;
    layout::record_from_lab_table(table, plan, file, rate_source)
}

/// A test's file (at `real`, shown as `shown`) read under its plan: a MATLAB file when it
/// ends in `.mat` ([`matlab_table`]), text otherwise; with the record's rate.
fn read_test_file(
    real: &Path,
    shown: &str,
    plan: &ReadPlan,
    rate_source: &str,
) -> Result<(Record, Sources, f64), CampaignError> {
    let is_mat = real
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mat"));
    if !is_mat {
        let text = read_text(real, false).map_err(|e| rename_file(e, shown))?;
        return read_planned_rate(&text, shown, plan, rate_source);
    }
    let bytes = read_regular(real, MAX_RECORD_BYTES, "largest plausible record")
        .map_err(|r| refusal(shown, r))?;
    let table = matlab_table(&bytes, shown, plan)?;
    layout::record_from_lab_table(table, plan, shown, rate_source)
}

/// The signals of a MATLAB file that a test uses, as a table: every mapped `column` (a
/// variable, `matrix:k`, a dSPACE signal by name or block path) and every variable named
/// like a project channel. Rows are samples (errors say "line" for the sample number).
fn matlab_table(bytes: &[u8], file: &str, plan: &ReadPlan) -> Result<CsvTable, CampaignError> {
    let mat_err = |e: crate::campaign::matlab::MatError| CampaignError::Matlab {
        file: file.to_string(),
        message: e.to_string(),
    };
    let mat = crate::campaign::matlab::read_mat(bytes, file).map_err(mat_err)?;
    let mut names: Vec<String> = plan.columns.values().map(|m| m.column.clone()).collect();
    for (name, _) in &mat.variables {
        let project = REQUIRED_CHANNELS.contains(&name.as_str()) || name == SPOOL_CHANNEL;
        if project && !names.contains(name) {
            names.push(name.clone());
        }
    }
    names.dedup();
    let mut columns = Vec::with_capacity(names.len());
    for name in &names {
        let x = mat.signal(name).map_err(mat_err)?;
        if let Some(bad) = x.iter().position(|v| !v.is_finite()) {
            return Err(CampaignError::Matlab {
                file: file.to_string(),
                message: format!("{file}: `{name}`: sample {} is not finite", bad + 1),
            });
        }
        columns.push(x);
    }
    let n = columns.first().map_or(0, Vec::len);
    if let Some((name, c)) = names.iter().zip(&columns).find(|(_, c)| c.len() != n) {
        return Err(CampaignError::Matlab {
            file: file.to_string(),
            message: format!(
                "{file}: `{name}` has {} samples but `{}` has {n}: the channels of a test must have one length",
                c.len(),
                names[0]
            ),
        });
    }
    if n == 0 {
        return Err(CampaignError::Matlab {
            file: file.to_string(),
            message: format!(
                "{file}: no samples in the mapped signals ({})",
                names.join(", ")
            ),
        });
    }
    Ok(CsvTable {
        bad: vec![None; names.len()],
        names,
        columns,
        header_line: 0,
        row_lines: (1..=n).collect(),
    })
}

/// The reference channels of a record: what `shaketable simulate` needs.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceRecord {
    pub sample_rate_hz: f64,
    pub time_s: Vec<f64>,
    pub ref_displacement_m: Vec<f64>,
    pub ref_velocity_m_s: Vec<f64>,
    pub ref_acceleration_m_s2: Vec<f64>,
}

impl ReferenceRecord {
    /// The controller inputs at every sample (external force zero).
    pub fn inputs(&self) -> Vec<crate::model::Inputs> {
        (0..self.time_s.len())
            .map(|k| crate::model::Inputs {
                reference: crate::model::Reference {
                    displacement_m: self.ref_displacement_m[k],
                    velocity_m_s: self.ref_velocity_m_s[k],
                    acceleration_m_s2: self.ref_acceleration_m_s2[k],
                },
                external_force_n: 0.0,
            })
            .collect()
    }
}

/// Read only `time_s` and the three reference channels of a campaign-format CSV (other
/// channels may be present or not). With `sample_rate_hz = None` the rate is inferred
/// from the time column (which must still be uniform).
pub fn read_reference(
    path: &Path,
    sample_rate_hz: Option<f64>,
) -> Result<ReferenceRecord, CampaignError> {
    let file = display(path);
    let text = read_text(path, false)?;
    let mut table = parse_csv(&text, &file, &ReadOptions::default(), true)?;
    require_channels(&table, &REFERENCE_CHANNELS, &file)?;
    let time = table.take("time_s").unwrap_or_default();
    let fs = check_time(
        &table,
        &time,
        sample_rate_hz,
        "the given sample rate",
        &file,
    )?;
    Ok(ReferenceRecord {
        sample_rate_hz: fs,
        time_s: time,
        ref_displacement_m: table.take("ref_displacement_m").unwrap_or_default(),
        ref_velocity_m_s: table.take("ref_velocity_m_s").unwrap_or_default(),
        ref_acceleration_m_s2: table.take("ref_acceleration_m_s2").unwrap_or_default(),
    })
}

fn dir_name(dir: &Path) -> String {
    dir.canonicalize()
        .ok()
        .as_deref()
        .unwrap_or(dir)
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "campaign".to_string())
}

/// The campaign folder with symlinks resolved (what "inside the folder" is measured against).
fn campaign_root(dir: &Path) -> Result<PathBuf, CampaignError> {
    dir.canonicalize().map_err(|source| CampaignError::Read {
        file: display(dir),
        source,
    })
}

/// `dir/campaign.toml` as text: a regular file inside the folder, within its size bound.
fn read_toml_text(root: &Path, dir: &Path) -> Result<(String, String), CampaignError> {
    let path = dir.join("campaign.toml");
    let file = display(&path);
    if let Err(Some(real)) = resolve_inside(root, dir, "campaign.toml") {
        return Err(CampaignError::Refused {
            file,
            message: format!(
                "resolves to {}, outside the campaign folder {}; only files inside it are read",
                real.display(),
                root.display()
            ),
        });
    }
    Ok((read_text(&path, true)?, file))
}

/// The same error naming `file` (the path as campaign.toml gives it, not the resolved one).
fn rename_file(e: CampaignError, file: &str) -> CampaignError {
    let mut e = e;
    match &mut e {
        CampaignError::Read { file: f, .. }
        | CampaignError::Write { file: f, .. }
        | CampaignError::Csv { file: f, .. }
        | CampaignError::Toml { file: f, .. }
        | CampaignError::Refused { file: f, .. }
        | CampaignError::Invalid { file: f, .. }
        | CampaignError::Matlab { file: f, .. } => *f = file.to_string(),
        // an output error names the path it could not write; never renamed
        CampaignError::Output(_) => {}
    }
    e
}
