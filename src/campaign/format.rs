//! Reading and writing campaigns on disk (`shared/spec/campaign-format.md`).
//!
//! Every bad input is a [`CampaignError`] naming the file and the physical line (1-based,
//! comment and blank lines counted) and, for campaign.toml, the key and the test; never a
//! panic and never a silently wrong result. Floats are written with `ryu` (shortest
//! round-trip representation), so a record read back is bit-for-bit the record written.
//!
//! Choices where the format page is silent:
//! - campaign.toml: `name` may be omitted (the directory name is used); `sample_rate_hz`,
//!   every `[geometry]` key, every `[controller]` gain and, per test, `name`, `file`,
//!   `kind`, `control` (+ `rms`, `band_hz` for random, `frequency_hz`, `amplitude_m` for
//!   sine/triangle) are required. Unknown keys are accepted and ignored, except inside
//!   `[controller]` and a test's `controller = {...}` override, where an unknown gain
//!   (e.g. a typo `Fv`) would silently change the physics, so it is an error.
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
use super::{
    Campaign, CampaignInfo, Control, ControllerOverride, Geometry, Record, TestKind, TestSpec,
};
use crate::params::{self, Controller, Rule};
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
            | CampaignError::Invalid { file, .. } => file,
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

// ---------------------------------------------------------------------------------------
// CSV records
// ---------------------------------------------------------------------------------------

/// A parsed CSV: channel names, columns, and the physical line of the header and of
/// every data row.
struct CsvTable {
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
    header_line: usize,
    row_lines: Vec<usize>,
}

impl CsvTable {
    fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    fn take(&mut self, name: &str) -> Option<Vec<f64>> {
        self.index(name)
            .map(|i| std::mem::take(&mut self.columns[i]))
    }
}

fn unquote(cell: &str) -> &str {
    let c = cell.trim();
    if c.len() >= 2 && c.starts_with('"') && c.ends_with('"') {
        c[1..c.len() - 1].trim()
    } else {
        c
    }
}

/// Parse CSV text: header, rows, every cell a finite number, no ragged rows.
fn parse_csv(text: &str, file: &str) -> Result<CsvTable, CampaignError> {
    let err = |line: usize, message: String| CampaignError::Csv {
        file: file.to_string(),
        line,
        message,
    };
    let mut names: Vec<String> = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut header_line = 0usize;
    let mut row_lines = Vec::new();
    let mut last_line = 0usize;
    // a UTF-8 byte-order mark (spreadsheet exports) is not part of the first channel name
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for (i, line) in lines_any(text).enumerate() {
        let line_no = i + 1;
        let trimmed = line.trim_start();
        if trimmed.is_empty() {
            continue;
        }
        last_line = line_no;
        if trimmed.starts_with('#') {
            continue;
        }
        if header_line == 0 {
            header_line = line_no;
            for (j, cell) in line.split(',').enumerate() {
                let name = unquote(cell);
                if name.is_empty() {
                    return Err(err(
                        line_no,
                        format!("header: column {} has no name", j + 1),
                    ));
                }
                if names.iter().any(|n| n == name) {
                    return Err(err(
                        line_no,
                        format!("header: channel `{name}` appears twice"),
                    ));
                }
                if name.parse::<f64>().is_ok() {
                    return Err(err(
                        line_no,
                        format!("header expected (channel names), found the number `{name}`"),
                    ));
                }
                names.push(name.to_string());
            }
            let cap = text.len() / (line.len() + 1).max(8);
            columns = (0..names.len()).map(|_| Vec::with_capacity(cap)).collect();
            continue;
        }
        let mut n = 0usize;
        for cell in line.split(',') {
            if n >= names.len() {
                let count = line.split(',').count();
                return Err(err(
                    line_no,
                    format!(
                        "ragged row: {count} cells but the header (line {header_line}) has {} channels",
                        names.len()
                    ),
                ));
            }
            let c = unquote(cell);
            let v: f64 = c.parse().map_err(|_| {
                if c.is_empty() {
                    err(line_no, format!("channel `{}`: empty cell", names[n]))
                } else {
                    err(
                        line_no,
                        format!("channel `{}`: `{c}` is not a number", names[n]),
                    )
                }
            })?;
            if !v.is_finite() {
                return Err(err(
                    line_no,
                    format!(
                        "channel `{}`: `{c}` is not finite (NaN or infinity)",
                        names[n]
                    ),
                ));
            }
            columns[n].push(v);
            n += 1;
        }
        if n != names.len() {
            return Err(err(
                line_no,
                format!(
                    "ragged row: {n} cells but the header (line {header_line}) has {} channels",
                    names.len()
                ),
            ));
        }
        row_lines.push(line_no);
    }
    if header_line == 0 {
        return Err(err(
            last_line.max(1),
            "empty record: no header line and no samples".to_string(),
        ));
    }
    if row_lines.is_empty() {
        return Err(err(
            header_line,
            "empty record: a header but no samples".to_string(),
        ));
    }
    Ok(CsvTable {
        names,
        columns,
        header_line,
        row_lines,
    })
}

fn require_channels(t: &CsvTable, required: &[&str], file: &str) -> Result<(), CampaignError> {
    let missing: Vec<&str> = required
        .iter()
        .copied()
        .filter(|c| t.index(c).is_none())
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(CampaignError::Csv {
        file: file.to_string(),
        line: t.header_line,
        message: format!(
            "missing required channel{} {} (the header has: {})",
            if missing.len() > 1 { "s" } else { "" },
            missing
                .iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(", "),
            t.names.join(", ")
        ),
    })
}

/// Check the time column: strictly increasing; its own rate (see [`TimeGrid`]) within
/// [`RATE_TOLERANCE`] of `sample_rate_hz` (or, when `None`, taken as the rate); every
/// sample on its uniform grid. Returns the sample rate.
fn check_time(
    t: &CsvTable,
    time: &[f64],
    sample_rate_hz: Option<f64>,
    rate_source: &str,
    file: &str,
) -> Result<f64, CampaignError> {
    let err = |line: usize, message: String| CampaignError::Csv {
        file: file.to_string(),
        line,
        message,
    };
    let n = time.len();
    for k in 1..n {
        if time[k] <= time[k - 1] {
            return Err(err(
                t.row_lines[k],
                format!(
                    "time_s is not increasing: {} after {} (line {})",
                    time[k],
                    time[k - 1],
                    t.row_lines[k - 1]
                ),
            ));
        }
    }
    if n < 2 {
        return match sample_rate_hz {
            Some(fs) => Ok(fs),
            None => Err(err(
                t.row_lines[0],
                "a single sample: the sample rate cannot be inferred from time_s".to_string(),
            )),
        };
    }
    let grid = TimeGrid::fit(time);
    let fs = match sample_rate_hz {
        Some(fs) => {
            let clock = grid.rate_hz();
            if ((clock - fs) / fs).abs() > RATE_TOLERANCE {
                return Err(err(
                    t.row_lines[1],
                    format!(
                        "sample rate disagrees: time column gives {} Hz, {rate_source} says {} Hz \
                         (more than {} % apart)",
                        num(round_sig(clock, 7)),
                        num(fs),
                        RATE_TOLERANCE * 100.0
                    ),
                ));
            }
            fs
        }
        None => {
            let fs = grid.rate_hz();
            if (fs - fs.round()).abs() < 1e-6 * fs {
                fs.round()
            } else {
                fs
            }
        }
    };
    if let Some(k) = grid.first_off_grid(time) {
        let expected = grid.at(k as f64);
        // a start at 0 shows as 0, not as the fit's rounding residue
        let t0 = if grid.t0.abs() < 1e-6 * grid.step {
            0.0
        } else {
            grid.t0
        };
        return Err(err(
            t.row_lines[k],
            format!(
                "non-uniform time: sample {k} is at time_s = {} but the time column's own \
                 uniform grid ({} Hz from {}) puts it at {} (step here {} s, expected {} s)",
                time[k],
                num(round_sig(grid.rate_hz(), 7)),
                num(t0),
                num(expected),
                num(round_sig(
                    if k > 0 { time[k] - time[k - 1] } else { 0.0 },
                    6
                )),
                num(round_sig(grid.step, 6)),
            ),
        ));
    }
    Ok(fs)
}

/// `x` for a message: 9 significant digits, exponent notation when very large or small.
fn num(x: f64) -> String {
    let r = round_sig(x, 9);
    if r != 0.0 && r.is_finite() && (r.abs() >= 1e7 || r.abs() < 1e-4) {
        format!("{r:e}")
    } else {
        format!("{r}")
    }
}

/// `x` rounded to `digits` significant digits (for messages).
fn round_sig(x: f64, digits: usize) -> f64 {
    format!("{x:.*e}", digits.saturating_sub(1))
        .parse()
        .unwrap_or(x)
}

/// The uniform grid a time column follows: `t0 + j * step`, fitted by least squares over
/// every sample, where `j` counts steps of the median step (so a gap counts as two steps
/// and does not bias the fit). The rate rule compares `1 / step` with the declared rate;
/// the uniformity rule compares each sample with this grid, so a small constant rate
/// offset never accumulates into "non-uniform time", and jitter, gaps and drift still do.
#[derive(Clone, Copy)]
struct TimeGrid {
    t0: f64,
    step: f64,
    median: f64,
}

impl TimeGrid {
    /// Fit the grid of a strictly increasing time column of at least 2 samples: a least
    /// squares line, then again without the samples off that line (so one late sample
    /// does not tilt the grid of a short record).
    fn fit(time: &[f64]) -> TimeGrid {
        let mut steps: Vec<f64> = time.windows(2).map(|w| w[1] - w[0]).collect();
        let mid = steps.len() / 2;
        let (_, &mut median, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
        let first = TimeGrid {
            t0: time[0],
            step: median,
            median,
        }
        .refit(time, None);
        first.refit(time, Some(GRID_TOLERANCE * first.step))
    }

    /// The least-squares grid of the samples within `tol` of this grid (all if `None`).
    fn refit(&self, time: &[f64], tol: Option<f64>) -> TimeGrid {
        let keep = |j: f64, t: f64| tol.is_none_or(|tol| (t - self.at(j)).abs() <= tol);
        let (mut n, mut sj, mut st) = (0.0, 0.0, 0.0);
        for (j, &t) in self.indices(time).zip(time) {
            if keep(j, t) {
                (n, sj, st) = (n + 1.0, sj + j, st + t);
            }
        }
        let (mj, mt) = (sj / n, st / n);
        let (mut sjt, mut sjj) = (0.0, 0.0);
        for (j, &t) in self.indices(time).zip(time) {
            if keep(j, t) {
                sjt += (j - mj) * (t - mt);
                sjj += (j - mj) * (j - mj);
            }
        }
        if !(n >= 2.0 && sjj > 0.0 && sjt > 0.0) {
            return *self;
        }
        let step = sjt / sjj;
        TimeGrid {
            t0: mt - step * mj,
            step,
            median: self.median,
        }
    }

    /// The grid time of index `j`.
    fn at(&self, j: f64) -> f64 {
        self.t0 + j * self.step
    }

    fn rate_hz(&self) -> f64 {
        1.0 / self.step
    }

    /// The grid index of every sample: each step counts as a whole number of median
    /// steps (1 normally, 2 across a missing sample), added one step at a time so that
    /// a small rate offset never rounds to the wrong index.
    fn indices<'a>(&self, time: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
        let median = self.median;
        let mut j = 0.0;
        let mut prev = time[0];
        time.iter().map(move |&t| {
            j += ((t - prev) / median).round();
            prev = t;
            j
        })
    }

    /// The first sample off its place `t0 + k * step` by more than [`GRID_TOLERANCE`]
    /// of a step (jitter, drift), or where a step is not one step (a gap, a doubled sample).
    fn first_off_grid(&self, time: &[f64]) -> Option<usize> {
        let tol = GRID_TOLERANCE * self.step;
        self.indices(time)
            .zip(time)
            .enumerate()
            .position(|(k, (j, &t))| j != k as f64 || (t - self.at(j)).abs() > tol)
    }
}

fn record_from_table(mut t: CsvTable) -> Record {
    let mut take = |name: &str| t.take(name).unwrap_or_default();
    let time_s = take("time_s");
    let ref_displacement_m = take("ref_displacement_m");
    let ref_velocity_m_s = take("ref_velocity_m_s");
    let ref_acceleration_m_s2 = take("ref_acceleration_m_s2");
    let valve_command = take("valve_command");
    let displacement_m = take("displacement_m");
    let acceleration_m_s2 = take("acceleration_m_s2");
    let force_n = take("force_n");
    let spool_position = t.take(SPOOL_CHANNEL);
    let known: Vec<&str> = REQUIRED_CHANNELS
        .iter()
        .copied()
        .chain(std::iter::once(SPOOL_CHANNEL))
        .collect();
    let extra = t
        .names
        .iter()
        .zip(t.columns.iter_mut())
        .filter(|(n, _)| !known.contains(&n.as_str()))
        .map(|(n, c)| (n.clone(), std::mem::take(c)))
        .collect();
    Record {
        time_s,
        ref_displacement_m,
        ref_velocity_m_s,
        ref_acceleration_m_s2,
        valve_command,
        spool_position,
        displacement_m,
        acceleration_m_s2,
        force_n,
        extra,
    }
}

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
    let table = parse_csv(text, file)?;
    require_channels(&table, &REQUIRED_CHANNELS, file)?;
    let time = &table.columns[table.index("time_s").unwrap_or(0)];
    check_time(&table, time, Some(sample_rate_hz), rate_source, file)?;
    Ok(record_from_table(table))
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
    let mut table = parse_csv(&text, &file)?;
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

/// The channels of a record in file order: required ones, the spool (if any), extras.
fn channels(record: &Record) -> Vec<(&str, &[f64])> {
    let mut c: Vec<(&str, &[f64])> = vec![
        ("time_s", &record.time_s),
        ("ref_displacement_m", &record.ref_displacement_m),
        ("ref_velocity_m_s", &record.ref_velocity_m_s),
        ("ref_acceleration_m_s2", &record.ref_acceleration_m_s2),
        ("valve_command", &record.valve_command),
    ];
    if let Some(s) = &record.spool_position {
        c.push((SPOOL_CHANNEL, s));
    }
    c.push(("displacement_m", &record.displacement_m));
    c.push(("acceleration_m_s2", &record.acceleration_m_s2));
    c.push(("force_n", &record.force_n));
    for (n, v) in &record.extra {
        c.push((n.as_str(), v));
    }
    c
}

/// The CSV text of a record (header + one row per sample, ryu floats).
pub fn record_to_csv(record: &Record, file: &str) -> Result<Vec<u8>, CampaignError> {
    let cols = channels(record);
    let n = record.len();
    let invalid = |message: String| CampaignError::Invalid {
        file: file.to_string(),
        message,
    };
    if n == 0 {
        return Err(invalid("empty record: no samples to write".to_string()));
    }
    let mut seen: Vec<&str> = Vec::with_capacity(cols.len());
    for (name, col) in &cols {
        if col.len() != n {
            return Err(invalid(format!(
                "channel `{name}` has {} samples but time_s has {n}",
                col.len()
            )));
        }
        if name.is_empty() || name.contains([',', '\n', '\r', '"']) || name.starts_with('#') {
            return Err(invalid(format!(
                "channel name `{name}` cannot be written in a CSV header"
            )));
        }
        if seen.contains(name) {
            return Err(invalid(format!("channel `{name}` appears twice")));
        }
        seen.push(name);
    }
    let mut out = Vec::with_capacity(n * cols.len() * 22 + 256);
    out.extend_from_slice(seen.join(",").as_bytes());
    out.push(b'\n');
    let mut buf = ryu::Buffer::new();
    for k in 0..n {
        for (j, (name, col)) in cols.iter().enumerate() {
            let v = col[k];
            if !v.is_finite() {
                return Err(invalid(format!(
                    "channel `{name}` sample {k} (would be line {}) is {v}: not writable",
                    k + 2
                )));
            }
            if j > 0 {
                out.push(b',');
            }
            out.extend_from_slice(buf.format_finite(v).as_bytes());
        }
        out.push(b'\n');
    }
    Ok(out)
}

/// Write one record as a campaign-format CSV.
pub fn write_record(record: &Record, path: &Path) -> Result<(), CampaignError> {
    let file = display(path);
    let bytes = record_to_csv(record, &file)?;
    write_bytes(path, &bytes)
}

/// Written atomically, never through a symlink ([`crate::output::atomic_write`]).
fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), CampaignError> {
    Ok(crate::output::atomic_write(path, bytes)?)
}

// ---------------------------------------------------------------------------------------
// campaign.toml
// ---------------------------------------------------------------------------------------

type RawTable = BTreeMap<Spanned<String>, Spanned<toml::Value>>;

#[derive(serde::Deserialize)]
struct RawDoc {
    name: Option<Spanned<toml::Value>>,
    sample_rate_hz: Option<Spanned<toml::Value>>,
    geometry: Option<Spanned<RawTable>>,
    controller: Option<Spanned<RawTable>>,
    test: Option<Spanned<Vec<Spanned<RawTable>>>>,
}

/// Line numbers from byte offsets.
struct Lines<'a> {
    text: &'a str,
    file: &'a str,
}

impl Lines<'_> {
    fn line(&self, offset: usize) -> usize {
        let end = offset.min(self.text.len());
        self.text.as_bytes()[..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1
    }

    fn err(
        &self,
        offset: Option<usize>,
        test: Option<&str>,
        key: Option<&str>,
        message: impl Into<String>,
    ) -> CampaignError {
        CampaignError::Toml {
            file: self.file.to_string(),
            line: offset.map(|o| self.line(o)),
            test: test.map(str::to_string),
            key: key.map(str::to_string),
            message: message.into(),
        }
    }
}

fn type_name(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::String(_) => "a string",
        toml::Value::Integer(_) => "an integer",
        toml::Value::Float(_) => "a float",
        toml::Value::Boolean(_) => "a boolean",
        toml::Value::Datetime(_) => "a date",
        toml::Value::Array(_) => "an array",
        toml::Value::Table(_) => "a table",
    }
}

fn as_number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// A plausible physical range (inclusive) of a campaign.toml value. The ranges are wide
/// (orders of magnitude beyond any real table either way): what they catch is a unit slip
/// (mm^2 for m^2) or a typo, and values like 1e300 that would overflow to `inf` downstream.
#[derive(Clone, Copy)]
struct Bound {
    min: f64,
    max: f64,
    unit: &'static str,
}

impl Bound {
    /// The range of a parameter rule ([`crate::params`], one source for the parameter
    /// file and campaign.toml); a rule without a range bounds nothing but the sign.
    const fn of(rule: Rule, unit: &'static str) -> Bound {
        match rule {
            Rule::Range { min, max, .. } => Bound { min, max, unit },
            _ => Bound {
                min: f64::MIN_POSITIVE,
                max: f64::MAX,
                unit,
            },
        }
    }
}

const PISTON_AREA_M2: Bound = Bound::of(params::PISTON_AREA_M2, "m^2");
const OIL_VOLUME_M3: Bound = Bound::of(params::OIL_VOLUME_M3, "m^3");
const SUPPLY_PRESSURE_PA: Bound = Bound::of(params::SUPPLY_PRESSURE_PA, "Pa");
const FLOW_GAIN_M3_S: Bound = Bound::of(params::FLOW_GAIN_M3_S, "m^3/s");
/// Sample rate: 1 Hz to 1 MHz (controllers sample at 0.5 to 10 kHz, fast DAQs 100 kHz).
const SAMPLE_RATE_HZ: Bound = Bound {
    min: 1.0,
    max: 1e6,
    unit: "Hz",
};
/// A test frequency (sine, triangle, band edge): from 1e-4 Hz (a period of 2.8 hours,
/// longer than any test) up to the Nyquist frequency (checked separately).
const TEST_FREQUENCY_HZ: Bound = Bound {
    min: 1e-4,
    max: 5e5,
    unit: "Hz",
};
/// A displacement level (amplitude, RMS): 1 nm (below any LVDT's resolution) to 10 m
/// (ten times the longest strokes, +-1 m).
const DISPLACEMENT_M: Bound = Bound {
    min: 1e-9,
    max: 10.0,
    unit: "m",
};
/// An acceleration level (RMS): 1 micro-g to 1000 g (a hundred times the strongest tables).
const ACCELERATION_M_S2: Bound = Bound {
    min: 1e-5,
    max: 1e4,
    unit: "m/s^2",
};
/// Largest magnitude of each TVC gain (spec section 2, u normalised to [-1, 1]): the gain
/// that opens the valve fully for an error of 1 nm, 1 nm/s, 1 nm/s^2 or 1 micro-newton,
/// a thousand times finer than any table's sensors resolve. The sign is not restricted
/// here: an unstable loop is reported by the stability check, not as a format error.
const GAIN_LIMITS: [(&str, f64, &str); 6] = [
    ("kp", 1e9, "1/m"),
    ("kv", 1e9, "s/m"),
    ("ka", 1e9, "s^2/m"),
    ("fv", 1e9, "s/m"),
    ("fa", 1e9, "s^2/m"),
    ("kdp", 1e6, "1/N"),
];

/// The rule `x` breaks against bound `b`, if any.
fn broken(x: f64, b: Bound) -> Option<String> {
    if !x.is_finite() {
        Some(format!("{x} must be finite"))
    } else if b.min > 0.0 && x <= 0.0 {
        Some(format!("{} must be a finite number > 0", num(x)))
    } else if !(b.min..=b.max).contains(&x) {
        Some(format!(
            "{} {u} is outside the plausible range {} to {} {u}",
            num(x),
            num(b.min),
            num(b.max),
            u = b.unit
        ))
    } else {
        None
    }
}

/// The magnitude bound of gain `key`.
fn gain_check(key: &str) -> Bound {
    let (_, max, unit) = GAIN_LIMITS
        .iter()
        .find(|(k, _, _)| *k == key)
        .copied()
        .unwrap_or(("", f64::MAX, ""));
    Bound {
        min: -max,
        max,
        unit,
    }
}

/// A number from a spanned value, checked.
fn number(
    lines: &Lines,
    v: &Spanned<toml::Value>,
    test: Option<&str>,
    key: &str,
    check: Bound,
) -> Result<f64, CampaignError> {
    let off = Some(v.span().start);
    let x = as_number(v.get_ref()).ok_or_else(|| {
        lines.err(
            off,
            test,
            Some(key),
            format!("expected a number, found {}", type_name(v.get_ref())),
        )
    })?;
    match broken(x, check) {
        Some(rule) => Err(lines.err(off, test, Some(key), rule)),
        None => Ok(x),
    }
}

fn lookup<'t>(t: &'t RawTable, key: &str) -> Option<&'t Spanned<toml::Value>> {
    t.iter().find(|(k, _)| k.get_ref() == key).map(|(_, v)| v)
}

/// A required number of a table whose header is at `table_off`.
fn required_number(
    lines: &Lines,
    t: &RawTable,
    table_off: usize,
    test: Option<&str>,
    key: &str,
    check: Bound,
    what: &str,
) -> Result<f64, CampaignError> {
    match lookup(t, key) {
        Some(v) => number(lines, v, test, key, check),
        None => Err(lines.err(
            Some(table_off),
            test,
            Some(key),
            format!("required key is missing ({what})"),
        )),
    }
}

fn required_string<'t>(
    lines: &Lines,
    t: &'t RawTable,
    table_off: usize,
    test: Option<&str>,
    key: &str,
    what: &str,
) -> Result<(&'t str, usize), CampaignError> {
    match lookup(t, key) {
        Some(v) => match v.get_ref() {
            toml::Value::String(s) => Ok((s.as_str(), v.span().start)),
            other => Err(lines.err(
                Some(v.span().start),
                test,
                Some(key),
                format!("expected a string, found {}", type_name(other)),
            )),
        },
        None => Err(lines.err(
            Some(table_off),
            test,
            Some(key),
            format!("required key is missing ({what})"),
        )),
    }
}

const GAINS: [&str; 6] = ["kp", "kv", "ka", "fv", "fa", "kdp"];

/// `[controller]`: every gain required, finite; unknown gains are errors.
fn read_controller(lines: &Lines, c: &Spanned<RawTable>) -> Result<Controller, CampaignError> {
    let off = c.span().start;
    let t = c.get_ref();
    for (k, _) in t.iter() {
        if !GAINS.contains(&k.get_ref().as_str()) {
            return Err(lines.err(
                Some(k.span().start),
                None,
                Some(&format!("controller.{}", k.get_ref())),
                format!(
                    "unknown controller gain; the gains are {}",
                    GAINS.join(", ")
                ),
            ));
        }
    }
    let g = |key: &str| {
        required_number(
            lines,
            t,
            off,
            None,
            key,
            gain_check(key),
            "every TVC gain of spec section 2 must be given in [controller]",
        )
        .map_err(|e| rename_key(e, &format!("controller.{key}")))
    };
    Ok(Controller {
        kp: g("kp")?,
        kv: g("kv")?,
        ka: g("ka")?,
        fv: g("fv")?,
        fa: g("fa")?,
        kdp: g("kdp")?,
    })
}

fn rename_key(e: CampaignError, new_key: &str) -> CampaignError {
    match e {
        CampaignError::Toml {
            file,
            line,
            test,
            message,
            ..
        } => CampaignError::Toml {
            file,
            line,
            test,
            key: Some(new_key.to_string()),
            message,
        },
        other => other,
    }
}

/// A test's `controller = { ... }` override.
fn read_override(
    lines: &Lines,
    v: &Spanned<toml::Value>,
    test: &str,
) -> Result<ControllerOverride, CampaignError> {
    let off = Some(v.span().start);
    let toml::Value::Table(t) = v.get_ref() else {
        return Err(lines.err(
            off,
            Some(test),
            Some("controller"),
            format!(
                "expected a table of gains like {{ fv = 0.0 }}, found {}",
                type_name(v.get_ref())
            ),
        ));
    };
    let mut o = ControllerOverride::default();
    for (k, val) in t {
        let key = format!("controller.{k}");
        let x = as_number(val).ok_or_else(|| {
            lines.err(
                off,
                Some(test),
                Some(&key),
                format!("expected a number, found {}", type_name(val)),
            )
        })?;
        if let Some(rule) = broken(x, gain_check(k)) {
            return Err(lines.err(off, Some(test), Some(&key), rule));
        }
        let slot = match k.as_str() {
            "kp" => &mut o.kp,
            "kv" => &mut o.kv,
            "ka" => &mut o.ka,
            "fv" => &mut o.fv,
            "fa" => &mut o.fa,
            "kdp" => &mut o.kdp,
            _ => {
                return Err(lines.err(
                    off,
                    Some(test),
                    Some(&key),
                    format!(
                        "unknown controller gain; the gains are {}",
                        GAINS.join(", ")
                    ),
                ))
            }
        };
        *slot = Some(x);
    }
    Ok(o)
}

/// A test's `file`, lexically (before any file system access): inside the campaign
/// folder, not the folder itself, not campaign.toml.
fn check_test_file(
    lines: &Lines,
    file: &str,
    file_off: usize,
    test: Option<&str>,
) -> Result<(), CampaignError> {
    let why = match normalise_relative(file) {
        None => "is outside the campaign folder: a test file must be a path inside it, relative to campaign.toml (not opened)",
        Some(p) if p.as_os_str().is_empty() => "names the campaign folder itself, not a file",
        Some(p) if p == Path::new("campaign.toml") => "is campaign.toml itself, not a record",
        Some(_) => return Ok(()),
    };
    Err(lines.err(
        Some(file_off),
        test,
        Some("file"),
        format!("`{file}` {why}"),
    ))
}

fn read_test(
    lines: &Lines,
    raw: &Spanned<RawTable>,
    index: usize,
    sample_rate_hz: f64,
) -> Result<(TestSpec, usize), CampaignError> {
    let off = raw.span().start;
    let t = raw.get_ref();
    let (name, _) = required_string(lines, t, off, None, "name", "every [[test]] needs a name")
        .map_err(|e| match e {
            CampaignError::Toml {
                file,
                line,
                key,
                message,
                ..
            } => CampaignError::Toml {
                file,
                line,
                test: Some(format!("#{} (unnamed)", index + 1)),
                key,
                message,
            },
            other => other,
        })?;
    let name = name.to_string();
    let tn = Some(name.as_str());
    if name.trim().is_empty() {
        return Err(lines.err(Some(off), tn, Some("name"), "test name is empty"));
    }
    let (file, file_off) = required_string(lines, t, off, tn, "file", "the CSV of the test")?;
    if file.trim().is_empty() {
        return Err(lines.err(Some(file_off), tn, Some("file"), "file name is empty"));
    }
    check_test_file(lines, file, file_off, tn)?;
    let (kind_s, kind_off) =
        required_string(lines, t, off, tn, "kind", "random | sine | triangle")?;
    let kind = match kind_s {
        "random" => TestKind::Random,
        "sine" => TestKind::Sine,
        "triangle" => TestKind::Triangle,
        other => {
            return Err(lines.err(
                Some(kind_off),
                tn,
                Some("kind"),
                format!("unknown kind `{other}`; expected random | sine | triangle"),
            ))
        }
    };
    let (control_s, control_off) =
        required_string(lines, t, off, tn, "control", "displacement | acceleration")?;
    let control = match control_s {
        "displacement" => Control::Displacement,
        "acceleration" => Control::Acceleration,
        other => {
            return Err(lines.err(
                Some(control_off),
                tn,
                Some("control"),
                format!("unknown control `{other}`; expected displacement | acceleration"),
            ))
        }
    };
    let mut spec = TestSpec {
        name: name.clone(),
        file: file.to_string(),
        kind,
        control,
        rms: None,
        band_hz: None,
        frequency_hz: None,
        amplitude_m: None,
        controller: ControllerOverride::default(),
    };
    let optional = |key: &str, check: Bound| -> Result<Option<f64>, CampaignError> {
        lookup(t, key)
            .map(|v| number(lines, v, tn, key, check))
            .transpose()
    };
    let level = match control {
        Control::Displacement => DISPLACEMENT_M,
        Control::Acceleration => ACCELERATION_M_S2,
    };
    spec.rms = optional("rms", level)?;
    spec.frequency_hz = optional("frequency_hz", TEST_FREQUENCY_HZ)?;
    spec.amplitude_m = optional("amplitude_m", DISPLACEMENT_M)?;
    if let Some(f) = spec.frequency_hz.filter(|&f| f > sample_rate_hz / 2.0) {
        let v = lookup(t, "frequency_hz").map(|v| v.span().start);
        return Err(lines.err(
            v,
            tn,
            Some("frequency_hz"),
            format!(
                "{f} Hz is above the Nyquist frequency {} Hz of sample_rate_hz",
                sample_rate_hz / 2.0
            ),
        ));
    }
    if let Some(v) = lookup(t, "band_hz") {
        let voff = Some(v.span().start);
        let bad = |m: String| lines.err(voff, tn, Some("band_hz"), m);
        let toml::Value::Array(a) = v.get_ref() else {
            return Err(bad(format!(
                "expected [low, high] in Hz, found {}",
                type_name(v.get_ref())
            )));
        };
        let nums: Vec<f64> = a.iter().filter_map(as_number).collect();
        if a.len() != 2 || nums.len() != 2 {
            return Err(bad("expected two numbers [low, high] in Hz".to_string()));
        }
        let (lo, hi) = (nums[0], nums[1]);
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
            return Err(bad(format!("[{lo}, {hi}]: need 0 <= low < high")));
        }
        if lo > 0.0 && lo < TEST_FREQUENCY_HZ.min {
            return Err(bad(format!(
                "[{lo}, {hi}]: a low edge above 0 must be at least {} Hz (0 for a band from DC)",
                TEST_FREQUENCY_HZ.min
            )));
        }
        if hi > sample_rate_hz / 2.0 {
            return Err(bad(format!(
                "[{lo}, {hi}]: the band goes above the Nyquist frequency {} Hz of sample_rate_hz",
                sample_rate_hz / 2.0
            )));
        }
        spec.band_hz = Some([lo, hi]);
    }
    match kind {
        TestKind::Random => {
            let why = "a random test needs its level (m RMS for displacement control, m/s^2 RMS for acceleration control)";
            if spec.rms.is_none() {
                return Err(lines.err(
                    Some(off),
                    tn,
                    Some("rms"),
                    format!("required key is missing ({why})"),
                ));
            }
            if spec.band_hz.is_none() {
                return Err(lines.err(
                    Some(off),
                    tn,
                    Some("band_hz"),
                    "required key is missing (a random test needs its band [low, high] in Hz)",
                ));
            }
        }
        TestKind::Sine | TestKind::Triangle => {
            let k = if kind == TestKind::Sine {
                "sine"
            } else {
                "triangle"
            };
            if spec.frequency_hz.is_none() {
                return Err(lines.err(
                    Some(off),
                    tn,
                    Some("frequency_hz"),
                    format!("required key is missing (a {k} test needs its frequency in Hz)"),
                ));
            }
            if spec.amplitude_m.is_none() {
                return Err(lines.err(
                    Some(off),
                    tn,
                    Some("amplitude_m"),
                    format!("required key is missing (a {k} test needs its displacement amplitude in m)"),
                ));
            }
        }
    }
    if let Some(v) = lookup(t, "controller") {
        spec.controller = read_override(lines, v, &name)?;
    }
    Ok((spec, file_off))
}

/// Parse campaign.toml text. `file` names it in errors; `default_name` is used when the
/// file has no `name`. Returns the info and, per test, the line of its `file` key.
pub fn parse_campaign_toml(
    text: &str,
    file: &str,
    default_name: &str,
) -> Result<(CampaignInfo, Vec<usize>), CampaignError> {
    // classic Mac line ends (a lone CR) read as line ends; offsets are unchanged
    let text = lone_cr_to_lf(text);
    let text: &str = &text;
    let lines = Lines { text, file };
    let doc: RawDoc = toml::from_str(text).map_err(|e| {
        let msg = e.message().trim().to_string();
        lines.err(
            e.span().map(|s| s.start),
            None,
            None,
            format!("not valid TOML: {msg}"),
        )
    })?;
    let name = match &doc.name {
        Some(v) => match v.get_ref() {
            toml::Value::String(s) => s.clone(),
            other => {
                return Err(lines.err(
                    Some(v.span().start),
                    None,
                    Some("name"),
                    format!("expected a string, found {}", type_name(other)),
                ))
            }
        },
        None => default_name.to_string(),
    };
    let sample_rate_hz = match &doc.sample_rate_hz {
        Some(v) => number(&lines, v, None, "sample_rate_hz", SAMPLE_RATE_HZ)?,
        None => {
            return Err(lines.err(
                None,
                None,
                Some("sample_rate_hz"),
                "required key is missing (the sampling rate of every record, Hz)",
            ))
        }
    };
    let geometry = match &doc.geometry {
        Some(g) => {
            let off = g.span().start;
            let get = |key: &str, bound: Bound| {
                required_number(
                    &lines,
                    g.get_ref(),
                    off,
                    None,
                    key,
                    bound,
                    "manufacturer geometry, spec section 4",
                )
                .map_err(|e| rename_key(e, &format!("geometry.{key}")))
            };
            Geometry {
                piston_area_m2: get("piston_area_m2", PISTON_AREA_M2)?,
                total_oil_volume_m3: get("total_oil_volume_m3", OIL_VOLUME_M3)?,
                supply_pressure_pa: get("supply_pressure_pa", SUPPLY_PRESSURE_PA)?,
                flow_gain_m3_s: get("flow_gain_m3_s", FLOW_GAIN_M3_S)?,
            }
        }
        None => {
            return Err(lines.err(
                None,
                None,
                Some("geometry"),
                "required table [geometry] is missing (piston_area_m2, total_oil_volume_m3, supply_pressure_pa, flow_gain_m3_s)",
            ))
        }
    };
    let controller = match &doc.controller {
        Some(c) => read_controller(&lines, c)?,
        None => {
            return Err(lines.err(
                None,
                None,
                Some("controller"),
                "required table [controller] is missing (kp, kv, ka, fv, fa, kdp)",
            ))
        }
    };
    let raw_tests = match &doc.test {
        Some(t) if !t.get_ref().is_empty() => t,
        Some(t) => {
            return Err(lines.err(
                Some(t.span().start),
                None,
                Some("test"),
                "the campaign has no tests",
            ))
        }
        None => {
            return Err(lines.err(
                None,
                None,
                Some("test"),
                "the campaign has no [[test]] entries",
            ))
        }
    };
    let mut tests: Vec<TestSpec> = Vec::new();
    let mut file_lines = Vec::new();
    let mut header_lines: Vec<usize> = Vec::new();
    for (i, raw) in raw_tests.get_ref().iter().enumerate() {
        let (spec, file_off) = read_test(&lines, raw, i, sample_rate_hz)?;
        let here = lines.line(raw.span().start);
        if let Some(j) = tests.iter().position(|t| t.name == spec.name) {
            return Err(lines.err(
                Some(raw.span().start),
                Some(&spec.name),
                Some("name"),
                format!(
                    "duplicate test name: already used by the test at line {}",
                    header_lines[j]
                ),
            ));
        }
        let same = |t: &TestSpec| normalise_relative(&t.file) == normalise_relative(&spec.file);
        if let Some(j) = tests.iter().position(same) {
            return Err(lines.err(
                Some(file_off),
                Some(&spec.name),
                Some("file"),
                format!(
                    "`{}` is already the file of test `{}` (line {})",
                    spec.file, tests[j].name, file_lines[j]
                ),
            ));
        }
        header_lines.push(here);
        file_lines.push(lines.line(file_off));
        tests.push(spec);
    }
    Ok((
        CampaignInfo {
            name,
            sample_rate_hz,
            geometry,
            controller,
            tests,
        },
        file_lines,
    ))
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

/// Read and check `dir/campaign.toml` only (records are not opened).
pub fn read_campaign_info(dir: &Path) -> Result<CampaignInfo, CampaignError> {
    let root = campaign_root(dir)?;
    let (text, file) = read_toml_text(&root, dir)?;
    Ok(parse_campaign_toml(&text, &file, &dir_name(dir))?.0)
}

/// Where each test's file is, checked before any record is read: inside the campaign
/// folder after resolving symlinks, a regular file within [`MAX_RECORD_BYTES`], and not
/// the file of another test nor campaign.toml (same device and inode: symlinks and hard
/// links included). Errors point at the test's `file` key.
fn locate_test_files(
    root: &Path,
    dir: &Path,
    info: &CampaignInfo,
    file_lines: &[usize],
    toml_file: &str,
) -> Result<Vec<PathBuf>, CampaignError> {
    use std::os::unix::fs::MetadataExt;
    let identity = |m: &std::fs::Metadata| (m.dev(), m.ino());
    let toml_id = std::fs::metadata(dir.join("campaign.toml"))
        .ok()
        .map(|m| identity(&m));
    let mut seen: Vec<((u64, u64), usize)> = Vec::new();
    let mut paths = Vec::with_capacity(info.tests.len());
    for (i, (spec, &line)) in info.tests.iter().zip(file_lines).enumerate() {
        let err = |message: String| CampaignError::Toml {
            file: toml_file.to_string(),
            line: Some(line),
            test: Some(spec.name.clone()),
            key: Some("file".to_string()),
            message,
        };
        let path = dir.join(&spec.file);
        let shown = display(&path);
        let real = match resolve_inside(root, dir, &spec.file) {
            Ok(real) => real,
            Err(Some(real)) => {
                return Err(err(format!(
                    "`{}` resolves to {}, outside the campaign folder {}; a test file must be inside it (not opened)",
                    spec.file,
                    real.display(),
                    root.display()
                )))
            }
            Err(None) => path.clone(),
        };
        let meta =
            std::fs::metadata(&real).map_err(|e| err(format!("cannot read {shown}: {e}")))?;
        if !meta.file_type().is_file() || meta.len() > MAX_RECORD_BYTES {
            let r = read_regular(&real, MAX_RECORD_BYTES, "largest plausible record");
            let why = r.err().map_or_else(String::new, |r| r.to_string());
            return Err(err(format!("{shown} {why}")));
        }
        let id = identity(&meta);
        if Some(id) == toml_id {
            return Err(err(format!(
                "{shown} is campaign.toml itself, not a record"
            )));
        }
        if let Some(&(_, j)) = seen.iter().find(|(s, _)| *s == id) {
            return Err(err(format!(
                "{shown} is the same file as `{}` of test `{}` (line {}): one file per test",
                info.tests[j].file, info.tests[j].name, file_lines[j]
            )));
        }
        seen.push((id, i));
        paths.push(real);
    }
    Ok(paths)
}

/// Read a whole campaign: campaign.toml and every record it lists, in parallel.
pub fn read_campaign(dir: &Path) -> Result<Campaign, CampaignError> {
    let root = campaign_root(dir)?;
    let (text, toml_file) = read_toml_text(&root, dir)?;
    let (info, file_lines) = parse_campaign_toml(&text, &toml_file, &dir_name(dir))?;
    let real = locate_test_files(&root, dir, &info, &file_lines, &toml_file)?;
    let fs = info.sample_rate_hz;
    let results: Vec<Result<Record, CampaignError>> = info
        .tests
        .par_iter()
        .zip(real.par_iter())
        .map(|(spec, real)| {
            let shown = display(&dir.join(&spec.file));
            let csv = read_text(real, false).map_err(|e| rename_file(e, &shown))?;
            read_record_str(&csv, &shown, fs, &toml_file)
        })
        .collect();
    let mut records = Vec::with_capacity(results.len());
    for r in results {
        records.push(r?);
    }
    Ok(Campaign {
        dir: dir.to_path_buf(),
        info,
        records,
    })
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
        | CampaignError::Invalid { file: f, .. } => *f = file.to_string(),
        // an output error names the path it could not write; never renamed
        CampaignError::Output(_) => {}
    }
    e
}

fn toml_float(x: f64) -> String {
    let mut b = ryu::Buffer::new();
    b.format(x).to_string()
}

fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// campaign.toml text for `info` (floats written shortest round-trip).
pub fn campaign_toml_string(info: &CampaignInfo) -> String {
    let mut s = String::new();
    s.push_str("# Campaign description (shared/spec/campaign-format.md).\n");
    s.push_str(&format!("name = {}\n", toml_string(&info.name)));
    s.push_str(&format!(
        "sample_rate_hz = {}\n\n",
        toml_float(info.sample_rate_hz)
    ));
    let g = &info.geometry;
    s.push_str("[geometry]\n");
    s.push_str(&format!(
        "piston_area_m2 = {}\n",
        toml_float(g.piston_area_m2)
    ));
    s.push_str(&format!(
        "total_oil_volume_m3 = {}\n",
        toml_float(g.total_oil_volume_m3)
    ));
    s.push_str(&format!(
        "supply_pressure_pa = {}\n",
        toml_float(g.supply_pressure_pa)
    ));
    s.push_str(&format!(
        "flow_gain_m3_s = {}\n\n",
        toml_float(g.flow_gain_m3_s)
    ));
    let c = &info.controller;
    s.push_str("[controller]\n");
    for (k, v) in [
        ("kp", c.kp),
        ("kv", c.kv),
        ("ka", c.ka),
        ("fv", c.fv),
        ("fa", c.fa),
        ("kdp", c.kdp),
    ] {
        s.push_str(&format!("{k} = {}\n", toml_float(v)));
    }
    for t in &info.tests {
        s.push_str("\n[[test]]\n");
        s.push_str(&format!("name = {}\n", toml_string(&t.name)));
        s.push_str(&format!("file = {}\n", toml_string(&t.file)));
        let kind = match t.kind {
            TestKind::Random => "random",
            TestKind::Sine => "sine",
            TestKind::Triangle => "triangle",
        };
        let control = match t.control {
            Control::Displacement => "displacement",
            Control::Acceleration => "acceleration",
        };
        s.push_str(&format!("kind = \"{kind}\"\ncontrol = \"{control}\"\n"));
        if let Some(x) = t.rms {
            s.push_str(&format!("rms = {}\n", toml_float(x)));
        }
        if let Some([lo, hi]) = t.band_hz {
            s.push_str(&format!(
                "band_hz = [{}, {}]\n",
                toml_float(lo),
                toml_float(hi)
            ));
        }
        if let Some(x) = t.frequency_hz {
            s.push_str(&format!("frequency_hz = {}\n", toml_float(x)));
        }
        if let Some(x) = t.amplitude_m {
            s.push_str(&format!("amplitude_m = {}\n", toml_float(x)));
        }
        let o = &t.controller;
        let gains: Vec<String> = [
            ("kp", o.kp),
            ("kv", o.kv),
            ("ka", o.ka),
            ("fv", o.fv),
            ("fa", o.fa),
            ("kdp", o.kdp),
        ]
        .iter()
        .filter_map(|(k, v)| v.map(|v| format!("{k} = {}", toml_float(v))))
        .collect();
        if !gains.is_empty() {
            s.push_str(&format!("controller = {{ {} }}\n", gains.join(", ")));
        }
    }
    s
}

/// Write `info` as `dir/campaign.toml`, creating `dir` if needed.
pub fn write_campaign_info(info: &CampaignInfo, dir: &Path) -> Result<(), CampaignError> {
    std::fs::create_dir_all(dir).map_err(|source| CampaignError::Write {
        file: display(dir),
        source,
    })?;
    let path = dir.join("campaign.toml");
    let text = campaign_toml_string(info);
    // what we write must read back (catches non-finite values, bad names, duplicates)
    parse_campaign_toml(&text, &display(&path), &info.name).map_err(|e| {
        CampaignError::Invalid {
            file: display(&path),
            message: format!("would not read back: {e}"),
        }
    })?;
    write_bytes(&path, text.as_bytes())
}

/// Write a whole campaign into `dir`: campaign.toml and one CSV per test (in parallel).
/// `campaign.dir` is ignored; `campaign.records[i]` goes to `dir/info.tests[i].file`.
pub fn write_campaign(campaign: &Campaign, dir: &Path) -> Result<(), CampaignError> {
    write_campaign_parts(&campaign.info, &campaign.records, dir)
}

/// [`write_campaign`] from its parts.
pub fn write_campaign_parts(
    info: &CampaignInfo,
    records: &[Record],
    dir: &Path,
) -> Result<(), CampaignError> {
    if records.len() != info.tests.len() {
        return Err(CampaignError::Invalid {
            file: display(&dir.join("campaign.toml")),
            message: format!(
                "{} tests listed but {} records given",
                info.tests.len(),
                records.len()
            ),
        });
    }
    write_campaign_info(info, dir)?;
    let paths: Vec<PathBuf> = info.tests.iter().map(|t| dir.join(&t.file)).collect();
    for p in &paths {
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).map_err(|source| CampaignError::Write {
                file: display(parent),
                source,
            })?;
        }
    }
    records
        .par_iter()
        .zip(paths.par_iter())
        .map(|(r, p)| write_record(r, p))
        .collect::<Result<Vec<()>, CampaignError>>()?;
    Ok(())
}
