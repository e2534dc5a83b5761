//! How a laboratory's files are read in place (campaign-format.md, "Recordings as
//! laboratories make them"): `[read]` (delimiter, header line, comments) and `[columns]`
//! (project channel = lab column, `value = scale * (raw - offset)`), each overridable per
//! test and merged key by key, and the record built from a file read that way: mapped
//! channels, the time base from the sample rate when no time column is mapped, and the
//! reference derivatives computed from the one reference that was recorded.

use super::csv::{check_time, CsvTable};
use super::{CampaignError, REQUIRED_CHANNELS, SPOOL_CHANNEL};
use crate::campaign::provenance::{ChannelSource, Source, Sources};
use crate::campaign::{Control, Record};
use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// The cell separator of a text record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Delimiter {
    Char(char),
    /// Any run of spaces and tabs (fixed-width and space-separated exports).
    Whitespace,
}

/// `[read]`: how the text of a record is read.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadOptions {
    pub delimiter: Delimiter,
    /// The 1-based physical line of the column names; `Some(0)`: no header (columns are
    /// named `1`, `2`, ...); `None`: the first line that is neither blank nor a comment
    /// (the project's own form, and `header_line = 1` for a file without comments).
    pub header_line: Option<usize>,
    /// Lines starting with it (after blanks) are skipped; empty: no comment lines.
    pub comment: String,
    /// The numbers' decimal separator: `.`, or `,` as spreadsheets and DAQ software
    /// write them under many European locales (`0,125` with `;` between cells).
    pub decimal: Decimal,
}

/// The decimal separator of a text record's numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Decimal {
    #[default]
    Point,
    Comma,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            delimiter: Delimiter::Char(','),
            header_line: None,
            comment: "#".to_string(),
            decimal: Decimal::Point,
        }
    }
}

/// A `[read]` table as written (campaign-wide or one test's override): unset keys are
/// taken from the level above.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadOverride {
    pub delimiter: Option<Delimiter>,
    pub header_line: Option<usize>,
    pub comment: Option<String>,
    pub decimal: Option<Decimal>,
}

impl ReadOptions {
    /// These options with `o`'s keys replacing theirs.
    pub fn merged(&self, o: &ReadOverride) -> ReadOptions {
        ReadOptions {
            delimiter: o.delimiter.unwrap_or(self.delimiter),
            header_line: o.header_line.or(self.header_line),
            comment: o.comment.clone().unwrap_or_else(|| self.comment.clone()),
            decimal: o.decimal.unwrap_or(self.decimal),
        }
    }
}

/// One `[columns]` entry as written: unset keys come from the campaign-wide entry of the
/// same channel when a test overrides it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ColumnEntry {
    pub column: Option<String>,
    pub scale: Option<f64>,
    pub offset: Option<f64>,
    /// `channel = false` in a test's `columns`: this test does not have the channel the
    /// campaign-wide `[columns]` maps (e.g. the displacement reference of an
    /// acceleration-controlled test).
    pub unmapped: bool,
}

/// A channel's source after merging: `value = scale * (raw - offset)`.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnMap {
    pub column: String,
    pub scale: f64,
    pub offset: f64,
}

/// `[columns]` merged with a test's `columns = {...}` (channel by channel, and key by key
/// within a channel). Err names the channel that ends up without a column.
pub fn merge_columns(
    campaign: &BTreeMap<String, ColumnEntry>,
    test: &BTreeMap<String, ColumnEntry>,
) -> Result<BTreeMap<String, ColumnMap>, String> {
    let mut out = BTreeMap::new();
    for channel in campaign.keys().chain(test.keys()) {
        let base = campaign.get(channel).cloned().unwrap_or_default();
        let over = test.get(channel).cloned().unwrap_or_default();
        if over.unmapped || out.contains_key(channel) {
            continue;
        }
        let column = over.column.or(base.column).ok_or_else(|| {
            format!("`{channel}` has a scale or offset but no `column` to read it from")
        })?;
        out.insert(
            channel.clone(),
            ColumnMap {
                column,
                scale: over.scale.or(base.scale).unwrap_or(1.0),
                offset: over.offset.or(base.offset).unwrap_or(0.0),
            },
        );
    }
    Ok(out)
}

/// Everything needed to read one test's file.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadPlan {
    pub read: ReadOptions,
    pub columns: BTreeMap<String, ColumnMap>,
    /// False for the project's own form (no `[read]` or `[columns]` anywhere): every
    /// cell must be a number and every channel of the first form is required as is.
    pub lab_form: bool,
    /// The test's rate: its own `sample_rate_hz`, else the campaign's; `None` when
    /// campaign.toml gives neither and the rate comes from the mapped time column.
    pub sample_rate_hz: Option<f64>,
    /// The line of campaign.toml giving the test's own `sample_rate_hz`, if it has one
    /// (named when the time column disagrees with it).
    pub own_rate_line: Option<usize>,
    pub control: Control,
}

impl ReadPlan {
    /// The project's own form at `sample_rate_hz`.
    pub fn project_form(sample_rate_hz: f64, control: Control) -> ReadPlan {
        ReadPlan {
            read: ReadOptions::default(),
            columns: BTreeMap::new(),
            lab_form: false,
            sample_rate_hz: Some(sample_rate_hz),
            own_rate_line: None,
            control,
        }
    }
}

/// The channels of a lab-form table after mapping, by project channel name, in a fixed
/// order (mapped channels, then unmapped project channels, then kept extras).
struct Mapped {
    channels: Vec<(String, Vec<f64>)>,
    /// Where each of `channels` came from.
    sources: Vec<ChannelSource>,
    /// The file's columns not read (text nobody mapped, a column shadowed by a mapping).
    unread: Vec<String>,
}

impl Mapped {
    fn take(&mut self, name: &str) -> Option<Vec<f64>> {
        let i = self.channels.iter().position(|(n, _)| n == name)?;
        Some(self.channels.remove(i).1)
    }
}

fn csv_err(file: &str, line: usize, message: String) -> CampaignError {
    CampaignError::Csv {
        file: file.to_string(),
        line,
        message,
    }
}

/// The project channels of a table under `plan`'s mapping; unmapped numeric columns are
/// kept under their own names, unmapped text columns (a date, an event note) dropped.
fn map_columns(t: &mut CsvTable, plan: &ReadPlan, file: &str) -> Result<Mapped, CampaignError> {
    let mut channels = Vec::new();
    let mut sources = Vec::new();
    let mut used = vec![false; t.names.len()];
    for (channel, m) in &plan.columns {
        let Some(j) = t.index(&m.column) else {
            return Err(csv_err(
                file,
                t.header_line.max(1),
                format!(
                    "column `{}` (mapped to `{channel}`) not found; the columns are: {}{}",
                    m.column,
                    t.names.join(", "),
                    delimiter_hint(t, plan.read.delimiter)
                ),
            ));
        };
        if let Some((line, why)) = &t.bad[j] {
            return Err(csv_err(
                file,
                *line,
                format!("{why} (mapped to `{channel}`)"),
            ));
        }
        used[j] = true;
        let values = t.columns[j]
            .iter()
            .map(|raw| m.scale * (raw - m.offset))
            .collect();
        channels.push((channel.clone(), values));
        sources.push(ChannelSource {
            channel: channel.clone(),
            source: Source::Column {
                column: m.column.clone(),
                scale: m.scale,
                offset: m.offset,
            },
        });
    }
    let mut unread = Vec::new();
    for (j, was_used) in used.into_iter().enumerate() {
        let name = t.names[j].clone();
        if was_used {
            continue;
        }
        if channels.iter().any(|(c, _)| *c == name) {
            unread.push(name);
            continue;
        }
        let project = REQUIRED_CHANNELS.contains(&name.as_str()) || name == SPOOL_CHANNEL;
        match (&t.bad[j], project) {
            (Some((line, why)), true) => return Err(csv_err(file, *line, why.clone())),
            (Some(_), false) => unread.push(name),
            (None, _) => {
                sources.push(ChannelSource {
                    channel: name.clone(),
                    source: Source::same_column(&name),
                });
                channels.push((name, std::mem::take(&mut t.columns[j])));
            }
        }
    }
    Ok(Mapped {
        channels,
        sources,
        unread,
    })
}

/// Other delimiters a header read as a single column may hold, in the order they are
/// suggested: a `;` export read at `,` still shows its spaces, so the characters come
/// before whitespace.
const OTHER_DELIMITERS: [(Delimiter, &str); 4] = [
    (Delimiter::Char(';'), "\";\""),
    (Delimiter::Char('\t'), "\"\\t\""),
    (Delimiter::Char(','), "\",\""),
    (Delimiter::Whitespace, "\"whitespace\""),
];

/// When the header was read as one column that holds another common delimiter, the hint
/// that the file seems to use it (a `;` export read at the default `,`); else empty.
fn delimiter_hint(t: &CsvTable, used: Delimiter) -> String {
    let [header] = t.names.as_slice() else {
        return String::new();
    };
    if t.header_line == 0 {
        return String::new();
    }
    let splits = |d: Delimiter| match d {
        Delimiter::Char(c) => header.split(c).filter(|f| !f.trim().is_empty()).count() > 1,
        Delimiter::Whitespace => header.split_whitespace().count() > 1,
    };
    match OTHER_DELIMITERS
        .iter()
        .find(|(d, _)| *d != used && splits(*d))
    {
        Some((_, shown)) => format!(
            " (the header is one column holding {shown}: the file seems to use {shown} as its \
             delimiter; set `[read] delimiter = {shown}`, or the test's `read = {{ delimiter = {shown} }}`)"
        ),
        None => String::new(),
    }
}

/// The measured responses a lab-form test needs at least one of (campaign-format.md).
const RESPONSES: [&str; 2] = ["displacement_m", "acceleration_m_s2"];

/// A lab-form record: the table mapped, the time base checked or made from the rate, the
/// reference derivatives computed from the recorded reference; where each channel came
/// from; and the record's sample rate (the plan's, else its time column's).
pub(super) fn record_from_lab_table(
    mut t: CsvTable,
    plan: &ReadPlan,
    file: &str,
    rate_source: &str,
) -> Result<(Record, Sources, f64), CampaignError> {
    let mut m = map_columns(&mut t, plan, file)?;
    let n = t.row_lines.len();
    let line = t.header_line.max(1);
    let (time_s, fs) = match (m.take("time_s"), plan.sample_rate_hz) {
        (Some(time), rate) => {
            let fs = check_time(&t, &time, rate, rate_source, file)?;
            (time, plausible_rate(fs, &t, file)?)
        }
        (None, Some(fs)) => ((0..n).map(|k| k as f64 / fs).collect(), fs),
        (None, None) => {
            return Err(csv_err(
                file,
                line,
                format!(
                    "no time base: no `time_s` after mapping and no `sample_rate_hz` in \
                     campaign.toml; the columns are: {}",
                    t.names.join(", ")
                ),
            ))
        }
    };
    let (x, v, a) = reference(&mut m, plan.control, fs).map_err(|why| csv_err(file, line, why))?;
    let valve_command = m.take("valve_command");
    let displacement_m = m.take("displacement_m");
    let acceleration_m_s2 = m.take("acceleration_m_s2");
    let force_n = m.take("force_n");
    let spool_position = m.take(SPOOL_CHANNEL);
    if displacement_m.is_none() && acceleration_m_s2.is_none() {
        return Err(csv_err(
            file,
            line,
            format!(
                "no measured response after mapping: map {} in [columns] (a test needs at \
                 least one); the columns are: {}",
                RESPONSES.join(" or "),
                t.names.join(", ")
            ),
        ));
    }
    let record = Record {
        time_s,
        ref_displacement_m: x,
        ref_velocity_m_s: v,
        ref_acceleration_m_s2: a,
        valve_command,
        spool_position,
        displacement_m,
        acceleration_m_s2,
        force_n,
        extra: m.channels,
    };
    let sources = sources_of(&record, m.sources, m.unread, plan.control, fs);
    Ok((record, sources, fs))
}

/// Rates a time column may give: those campaign.toml may (1 Hz to 1 MHz); beyond them the
/// column's unit is wrong (a column in ms read as seconds gives 1/1000 of the rate, below
/// 1 Hz for any record sampled under 1 kHz).
const PLAUSIBLE_RATE_HZ: std::ops::RangeInclusive<f64> = 1.0..=1e6;

/// `fs`, the rate of a time column, if plausible; else the error naming the file.
fn plausible_rate(fs: f64, t: &CsvTable, file: &str) -> Result<f64, CampaignError> {
    if PLAUSIBLE_RATE_HZ.contains(&fs) {
        return Ok(fs);
    }
    Err(csv_err(
        file,
        t.row_lines.get(1).copied().unwrap_or(t.header_line),
        format!(
            "the time column gives {fs} Hz, outside the plausible 1 Hz to 1 MHz: is its unit \
             seconds? (scale a column in ms with `time_s = {{ column = ..., scale = 0.001 }}`)"
        ),
    ))
}

/// Where each channel of `record` came from: a column (`read`), else made in reading
/// (the time base from the rate, a reference computed from the recorded one).
fn sources_of(
    record: &Record,
    read: Vec<ChannelSource>,
    unread_columns: Vec<String>,
    control: Control,
    sample_rate_hz: f64,
) -> Sources {
    let channels = record
        .channels()
        .into_iter()
        .map(|(name, _)| {
            let source = match read.iter().find(|c| c.channel == name) {
                Some(c) => c.source.clone(),
                None if name == "time_s" => Source::SampleRate { sample_rate_hz },
                None => Source::computed_reference(control, name),
            };
            ChannelSource {
                channel: name.to_string(),
                source,
            }
        })
        .collect();
    Sources {
        channels,
        unread_columns,
    }
}

type Reference = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The three reference channels: those recorded, the others computed in the frequency
/// domain from the one the test's control names (displacement: derivatives;
/// acceleration: integrals corrected to rest, see `integrate.rs`).
fn reference(m: &mut Mapped, control: Control, fs: f64) -> Result<Reference, String> {
    let (xd, vd, ad) = (
        m.take("ref_displacement_m"),
        m.take("ref_velocity_m_s"),
        m.take("ref_acceleration_m_s2"),
    );
    match (control, xd, ad) {
        (Control::Displacement, Some(x), a) => {
            let v = vd.unwrap_or_else(|| spectral(&x, fs, 1));
            let a = a.unwrap_or_else(|| spectral(&x, fs, 2));
            Ok((x, v, a))
        }
        (Control::Acceleration, x, Some(a)) => {
            let (vi, xi) = super::integrate::velocity_and_displacement(&a, fs);
            Ok((x.unwrap_or(xi), vd.unwrap_or(vi), a))
        }
        (Control::Displacement, None, _) => Err(
            "no `ref_displacement_m` after mapping: a displacement-controlled test needs its reference displacement".into(),
        ),
        (Control::Acceleration, _, None) => Err(
            "no `ref_acceleration_m_s2` after mapping: an acceleration-controlled test needs its reference acceleration".into(),
        ),
    }
}

/// The `order`-th derivative (negative: integral, mean removed) of `x` in the frequency
/// domain, on its even extension `x, reversed x` so that the ends do not jump (a
/// periodic extension of a record that ends elsewhere than it starts rings over the whole
/// record). Derivatives of the extension are exact for band-limited data away from the
/// ends; at the ends a derivative of odd order goes to zero (the extension's symmetry).
pub fn spectral(x: &[f64], fs: f64, order: i32) -> Vec<f64> {
    let n = x.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let m = 2 * n;
    let mut planner = RealFftPlanner::<f64>::new();
    let (fwd, inv) = (planner.plan_fft_forward(m), planner.plan_fft_inverse(m));
    let mut ext: Vec<f64> = x.iter().chain(x.iter().rev()).copied().collect();
    let mut spec = fwd.make_output_vec();
    // lengths match the plans, so these cannot fail
    let _ = fwd.process(&mut ext, &mut spec);
    let last = spec.len() - 1;
    for (k, c) in spec.iter_mut().enumerate() {
        let w = 2.0 * PI * k as f64 * fs / m as f64;
        *c = if k == 0 || (k == last && order % 2 != 0) {
            Complex::new(0.0, 0.0)
        } else {
            *c * Complex::new(0.0, w).powi(order) / m as f64
        };
    }
    let mut out = inv.make_output_vec();
    let _ = inv.process(&mut spec, &mut out);
    out.truncate(n);
    out
}
