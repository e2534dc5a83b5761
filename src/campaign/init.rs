//! `campaign init`: a campaign.toml skeleton for the files a laboratory has
//! (campaign-format.md, "Finding out what a file holds"). Each text file is sniffed from
//! its first lines: the delimiter, the header line, its columns with a few values, and a
//! sample rate from the acquisition software's preamble or from a time column. A MATLAB
//! file is read whole (`init/mat.rs`): its variables, matrix columns and dSPACE signals.
//! The channel mapping is left to the user, commented, with what was found beside it.
//! Every file not described is listed with the reason.

use super::files::{decode_utf8, lines_any, read_head};

mod mat;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How much of each file is read to sniff it: a preamble and a few hundred rows.
const HEAD_BYTES: u64 = 256 * 1024;
/// Rows looked at to choose the delimiter and find where the data starts.
const SNIFF_ROWS: usize = 200;
/// A guessed rate this close (relative) to a whole number of Hz is that number: the
/// rounding of a step such as 0.001 s in binary, not a real offset.
const RATE_ROUNDING: f64 = 1e-9;
/// Values shown per column.
const SAMPLE_VALUES: usize = 3;
/// Files larger than this are not records anyone exports as text or MAT (a disk image,
/// a video): listed as skipped.
const MAX_FILE_BYTES: u64 = super::files::MAX_RECORD_BYTES;

/// What was found in one file.
#[derive(Debug, Clone, PartialEq)]
pub struct Sniffed {
    pub file: String,
    /// How a text file is read; `None` for a MATLAB file.
    pub read: Option<TextRead>,
    pub columns: Vec<ColumnSample>,
    /// A sample rate and where it came from.
    pub sample_rate: Option<(f64, String)>,
}

/// How a text file is read: its `[read]` keys.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextRead {
    pub delimiter: &'static str,
    /// 1-based line of the column names; 0: no header.
    pub header_line: usize,
    /// The numbers' decimal separator, `.` or `,`.
    pub decimal: &'static str,
}

impl TextRead {
    /// The keys as a TOML inline table's body: `delimiter = ";", header_line = 1` and
    /// `decimal = ","` when the numbers have a decimal comma.
    fn keys(&self, separator: &str) -> String {
        let mut keys = vec![
            format!(
                "delimiter = {}",
                toml::Value::String(self.delimiter.to_string())
            ),
            format!("header_line = {}", self.header_line),
        ];
        if self.decimal == "," {
            keys.push("decimal = \",\"".to_string());
        }
        keys.join(separator)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct ColumnSample {
    /// What a `column` key names: a text column's header, a MATLAB variable, `matrix:k`,
    /// a dSPACE signal's name or block path.
    pub name: String,
    /// The first values as written (numbers or text).
    pub values: Vec<String>,
    pub numeric: bool,
    /// What else is known of it (a MATLAB file: its size, a dSPACE signal's block path,
    /// unit and time vector); empty for a text column.
    pub note: String,
}

/// A file that was not sniffed, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Skipped {
    pub file: String,
    pub why: String,
}

/// How cells may be separated and what the numbers' decimal separator is: a decimal
/// comma only where the comma does not separate cells. Of dialects that read a head
/// equally well the last listed is taken: a decimal point over a decimal comma (a file
/// without commas reads alike under both).
const DIALECTS: [Dialect; 7] = [
    Dialect::new(";", Some(';'), true),
    Dialect::new("\t", Some('\t'), true),
    Dialect::new("whitespace", None, true),
    Dialect::new(",", Some(','), false),
    Dialect::new(";", Some(';'), false),
    Dialect::new("\t", Some('\t'), false),
    Dialect::new("whitespace", None, false),
];

/// A delimiter (its `[read]` name and character; `None`: whitespace) and whether the
/// numbers have a decimal comma.
#[derive(Debug, Clone, Copy)]
struct Dialect {
    name: &'static str,
    delimiter: Option<char>,
    decimal_comma: bool,
}

impl Dialect {
    const fn new(name: &'static str, delimiter: Option<char>, decimal_comma: bool) -> Self {
        Dialect {
            name,
            delimiter,
            decimal_comma,
        }
    }

    fn split<'a>(&self, line: &'a str) -> Vec<&'a str> {
        match self.delimiter {
            Some(c) => line.split(c).map(str::trim).collect(),
            None => line.split_whitespace().collect(),
        }
    }

    fn number(&self, cell: &str) -> Option<f64> {
        let cell = cell.trim().trim_matches('"');
        match self.decimal_comma {
            true => cell.replace(',', ".").parse().ok(),
            false => cell.parse().ok(),
        }
    }

    fn is_number(&self, cell: &str) -> bool {
        self.number(cell).is_some()
    }

    /// A line is a data row when it has more than one cell and most are numbers.
    fn numeric_row(&self, line: &str) -> bool {
        let cells = self.split(line);
        let numbers = cells.iter().filter(|c| self.is_number(c)).count();
        cells.len() > 1 && 2 * numbers > cells.len()
    }
}

/// Sniff one text file's head.
pub fn sniff_text(file: &str, text: &str) -> Option<Sniffed> {
    let lines: Vec<&str> = lines_any(text).take(SNIFF_ROWS * 4).collect();
    // the dialect whose data rows are the most numerous, then whose rows hold the most
    // numbers ("0,5;1,2" is a row of two numbers, not of "0", "5;1" and "2")
    let d = DIALECTS.iter().copied().max_by_key(|d| {
        let rows = lines.iter().filter(|l| d.numeric_row(l));
        let numbers: usize = rows
            .clone()
            .map(|l| d.split(l).iter().filter(|c| d.is_number(c)).count())
            .sum();
        (rows.count(), numbers)
    })?;
    let first_data = lines.iter().position(|l| d.numeric_row(l))?;
    let width = d.split(lines[first_data]).len();
    // the header: the nearest non-blank line above the data with as many cells
    let header = (0..first_data)
        .rev()
        .find(|&i| !lines[i].trim().is_empty())
        .filter(|&i| d.split(lines[i]).len() >= width - 1 && !d.numeric_row(lines[i]));
    let names: Vec<String> = match header {
        Some(i) => d
            .split(lines[i])
            .iter()
            .map(|c| c.trim_matches('"').to_string())
            .collect(),
        None => (1..=width).map(|j| j.to_string()).collect(),
    };
    let rows: Vec<Vec<&str>> = lines[first_data..]
        .iter()
        .filter(|l| !l.trim().is_empty())
        .map(|l| d.split(l))
        .collect();
    let columns = names
        .iter()
        .enumerate()
        .map(|(j, name)| {
            let cells: Vec<&str> = rows
                .iter()
                .map(|r| r.get(j).copied().unwrap_or(""))
                .collect();
            ColumnSample {
                name: name.clone(),
                values: cells
                    .iter()
                    .take(SAMPLE_VALUES)
                    .map(|c| c.to_string())
                    .collect(),
                numeric: cells
                    .iter()
                    .filter(|c| !c.is_empty())
                    .all(|c| d.is_number(c)),
                note: String::new(),
            }
        })
        .collect();
    let sample_rate =
        preamble_rate(&lines[..first_data]).or_else(|| time_column_rate(&names, &rows, d));
    Some(Sniffed {
        file: file.to_string(),
        read: Some(TextRead {
            delimiter: d.name,
            header_line: header.map_or(0, |i| i + 1),
            decimal: if d.decimal_comma { "," } else { "." },
        }),
        columns,
        sample_rate,
    })
}

/// "Sampling Rate: 1000" or "Sampling Interval: 0.001" in a preamble.
fn preamble_rate(preamble: &[&str]) -> Option<(f64, String)> {
    for line in preamble {
        let lower = line.to_ascii_lowercase();
        let value = || {
            line.split([':', '='])
                .nth(1)
                .and_then(|v| v.split_whitespace().next())
                .and_then(|v| v.parse::<f64>().ok())
                .filter(|v| v.is_finite() && *v > 0.0)
        };
        if lower.contains("rate") && (lower.contains("sampl") || lower.contains("hz")) {
            if let Some(v) = value() {
                return Some((v, format!("\"{}\" in its preamble", line.trim())));
            }
        }
        if lower.contains("interval") || lower.contains("sample time") || lower.contains("dt") {
            if let Some(v) = value() {
                return Some((1.0 / v, format!("\"{}\" in its preamble", line.trim())));
            }
        }
    }
    None
}

/// Whether a column or variable is named like time (`t`, `Time_ms`, `Zeit`, `tiempo`).
fn is_time_name(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n == "t" || n.starts_with("time") || n.starts_with("zeit") || n.starts_with("tiempo")
}

/// The rate of times `t` (seconds assumed) from their median positive step.
fn median_step_rate(t: &[f64]) -> Option<f64> {
    let mut steps: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|s| s.is_finite() && *s > 0.0)
        .collect();
    if steps.is_empty() {
        return None;
    }
    steps.sort_by(f64::total_cmp);
    let fs = 1.0 / steps[steps.len() / 2];
    // a step of 0.001 s written in binary is 999.9999999999991 Hz: the rate meant is 1000
    let whole = fs.round();
    Some(if (fs - whole).abs() < RATE_ROUNDING * fs {
        whole
    } else {
        fs
    })
}

/// The rate of a column named like time, from its median step (seconds assumed).
fn time_column_rate(names: &[String], rows: &[Vec<&str>], d: Dialect) -> Option<(f64, String)> {
    let j = names.iter().position(|n| is_time_name(n))?;
    let t: Vec<f64> = rows
        .iter()
        .filter_map(|r| r.get(j).and_then(|c| d.number(c)))
        .collect();
    Some((
        median_step_rate(&t)?,
        format!(
            "the median step of column `{}`, read as seconds (set its scale if it is not)",
            names[j]
        ),
    ))
}

/// Sniff every regular file of `dir` (not campaign.toml, not hidden files), sorted.
pub fn sniff_dir(dir: &Path) -> std::io::Result<(Vec<Sniffed>, Vec<Skipped>)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    let (mut found, mut skipped) = (Vec::new(), Vec::new());
    for path in files {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name == "campaign.toml" || name.starts_with('.') {
            continue;
        }
        match sniff_file(&path, &name) {
            Ok(s) => found.push(s),
            Err(why) => skipped.push(Skipped { file: name, why }),
        }
    }
    Ok((found, skipped))
}

fn sniff_file(path: &Path, name: &str) -> Result<Sniffed, String> {
    let len = std::fs::metadata(path).map_err(|e| e.to_string())?.len();
    if len > MAX_FILE_BYTES {
        return Err(format!("{len} bytes, larger than any plausible record"));
    }
    let head = read_head(path, HEAD_BYTES).map_err(|r| r.to_string())?;
    let mat_name = Path::new(name)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mat"));
    if head.starts_with(b"MATLAB") || mat_name {
        return mat::sniff_mat_file(path, name);
    }
    let mut head = head;
    // a head cut inside a multi-byte character or a line: keep whole lines
    if len > HEAD_BYTES {
        if let Some(cut) = head.iter().rposition(|&b| b == b'\n') {
            head.truncate(cut + 1);
        }
    }
    let text = decode_utf8(head).map_err(|b| format!("not text: {b}"))?;
    sniff_text(name, &text).ok_or_else(|| "no rows of numbers found".to_string())
}

/// campaign.toml skeleton text for the sniffed files (`name` from the folder).
pub fn skeleton(name: &str, found: &[Sniffed], skipped: &[Skipped]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# campaign.toml written by `shaketable campaign init`: what was found in each file,"
    );
    let _ = writeln!(s, "# and the mapping to fill in (shared/spec/campaign-format.md, \"Recordings as laboratories make them\").");
    let _ = writeln!(s, "name = {}", toml::Value::String(name.to_string()));
    let rate = found.iter().find_map(|f| f.sample_rate.clone());
    match &rate {
        Some((fs, from)) => {
            let f = found
                .iter()
                .find(|f| f.sample_rate.is_some())
                .map_or("", |f| f.file.as_str());
            let _ = writeln!(
                s,
                "sample_rate_hz = {fs:?}    # guessed from {} of {f}: check it",
                from.replace('"', "'")
            );
        }
        None => {
            let _ = writeln!(
                s,
                "sample_rate_hz = 0.0    # FILL IN: no preamble or time column gave a rate"
            );
        }
    }
    s.push_str(GEOMETRY_AND_CONTROLLER);
    let common = most_common_read(found);
    if let Some(r) = common {
        let _ = writeln!(s, "\n[read]\n{}", r.keys("\n"));
    }
    s.push_str(COLUMNS_HELP);
    let campaign_rate = rate.as_ref().map(|(fs, _)| *fs);
    for f in found {
        s.push_str(&test_entry(f, common, campaign_rate));
    }
    for k in skipped {
        let _ = writeln!(s, "\n# skipped {}: {}", k.file, k.why);
    }
    s
}

/// The `[read]` of most text files; `None` when there is no text file.
fn most_common_read(found: &[Sniffed]) -> Option<TextRead> {
    let mut counts: Vec<(TextRead, usize)> = Vec::new();
    for key in found.iter().filter_map(|f| f.read) {
        match counts.iter_mut().find(|(k, _)| *k == key) {
            Some((_, n)) => *n += 1,
            None => counts.push((key, 1)),
        }
    }
    counts.iter().max_by_key(|(_, n)| *n).map(|(k, _)| *k)
}

/// The `[[test]]` entry of file `f`; its own `sample_rate_hz` when the rate guessed from
/// it differs from the campaign's `campaign_rate` (campaign-format.md: a test may set its
/// own).
fn test_entry(f: &Sniffed, common: Option<TextRead>, campaign_rate: Option<f64>) -> String {
    let mut s = String::new();
    let stem = Path::new(&f.file)
        .file_stem()
        .map_or(f.file.clone(), |x| x.to_string_lossy().into_owned());
    let _ = writeln!(
        s,
        "\n[[test]]\nname = {}\nfile = {}",
        toml::Value::String(stem),
        toml::Value::String(f.file.clone())
    );
    let _ = writeln!(
        s,
        "kind = \"record\"          # random | sine | triangle | record (FILL IN)"
    );
    let _ = writeln!(
        s,
        "control = \"displacement\"  # displacement | acceleration (FILL IN)"
    );
    if let Some((fs, from)) = f
        .sample_rate
        .as_ref()
        .filter(|(fs, _)| Some(*fs) != campaign_rate)
    {
        let _ = writeln!(
            s,
            "sample_rate_hz = {fs:?}    # guessed from {}: check it",
            from.replace('"', "'")
        );
    }
    if let (None, Some(fs)) = (&f.sample_rate, campaign_rate) {
        let _ = writeln!(
            s,
            "# sample_rate_hz = {fs:?}    # FILL IN if not the campaign's: no rate found in {}",
            f.file
        );
    }
    let Some(read) = f.read else {
        s.push_str(&mat::listing(f));
        return s;
    };
    if Some(read) != common {
        let _ = writeln!(s, "read = {{ {} }}", read.keys(", "));
    }
    let _ = writeln!(
        s,
        "# columns of {} (header line {}):",
        f.file, read.header_line
    );
    for c in &f.columns {
        let kind = if c.numeric { "" } else { " (text)" };
        let _ = writeln!(s, "#   {:?}{kind}: {}", c.name, c.values.join(", "));
    }
    s
}

const GEOMETRY_AND_CONTROLLER: &str = r#"
# Manufacturer geometry and controller gains, where known (FILL IN what you know).
[geometry]
# piston_area_m2 = 0.0911
# total_oil_volume_m3 = 0.12101
# supply_pressure_pa = 28.0e6
# flow_gain_m3_s = 0.2

[controller]
# kp = 10.0
# kv = 0.0
# ka = 0.0
# fv = 0.0
# fa = 0.0
# kdp = 0.0
"#;

const COLUMNS_HELP: &str = r#"
[columns]
# project channel = { column = "lab column", scale = ..., offset = ... }: value = scale * (raw - offset)
# time_s = { column = "Time", scale = 0.001 }                 # absent: time from sample_rate_hz; present: sample_rate_hz may go
# ref_displacement_m = { column = "...", scale = 0.01 }       # or ref_acceleration_m_s2 for acceleration control
# displacement_m = { column = "...", scale = 0.01 }
# acceleration_m_s2 = { column = "...", scale = 9.80665 }
# force_n = { column = "...", scale = 9806.65 }
# valve_command = "..."
# spool_position = "..."
"#;

#[cfg(test)]
mod tests {
    use super::*;

    fn read(delimiter: &'static str, header_line: usize) -> TextRead {
        TextRead {
            delimiter,
            header_line,
            decimal: ".",
        }
    }

    const DAQ: &str = "Header Size:  7\nVersion:  2\nSampling Interval:  0.001\nSampling Rate:  1000\nSample Count:  3\nDevice Serial Number:  0\nSample Number, Date/Time, CHANNEL0, CHANNEL1, CHANNEL2, Events\n         1,   06/29/2022 04:05:36.674 PM, -0.0209, -0.0166, -0.0169, DAQ Start\n         2,   06/29/2022 04:05:36.675 PM, -0.0221, -0.0166, -0.0167\n         3,   06/29/2022 04:05:36.676 PM, -0.0221, -0.0175, -0.0176\n";

    #[test]
    fn a_daq_export_is_sniffed() {
        let s = sniff_text("0A.txt", DAQ).unwrap();
        assert_eq!(s.read, Some(read(",", 7)));
        let names: Vec<&str> = s.columns.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "Sample Number",
                "Date/Time",
                "CHANNEL0",
                "CHANNEL1",
                "CHANNEL2",
                "Events"
            ]
        );
        assert!(s.columns[2].numeric && !s.columns[1].numeric);
        assert_eq!(s.columns[2].values, ["-0.0209", "-0.0221", "-0.0221"]);
        assert_eq!(s.sample_rate.unwrap().0, 1000.0);
    }

    #[test]
    fn whitespace_without_header_and_a_time_column() {
        let text = "0.000 1.0 2.0\n0.002 1.1 2.1\n0.004 1.2 2.2\n";
        let s = sniff_text("x.dat", text).unwrap();
        assert_eq!(s.read, Some(read("whitespace", 0)));
        assert_eq!(s.columns.len(), 3);
        assert!(s.sample_rate.is_none(), "no column is named like time");
        let text = "time;x;y\n0.000;1.0;2.0\n0.002;1.1;2.1\n0.004;1.2;2.2\n";
        let s = sniff_text("y.csv", text).unwrap();
        assert_eq!(s.read, Some(read(";", 1)));
        let (fs, _) = s.sample_rate.unwrap();
        assert!((fs - 500.0).abs() < 1e-9, "{fs}");
    }

    /// A decimal comma between `;` cells (a European locale's export) is found, and its
    /// time column gives the rate; commas that separate cells stay the delimiter.
    #[test]
    fn a_decimal_comma_is_sniffed() {
        let text = "Zeit;Soll;Ist\n0,000;1,5;2,25\n0,005;1,6;2,5\n0,010;1,7;2,75\n";
        let s = sniff_text("run.csv", text).unwrap();
        let mut expected = read(";", 1);
        expected.decimal = ",";
        assert_eq!(s.read, Some(expected));
        let (fs, _) = s.sample_rate.unwrap();
        assert!((fs - 200.0).abs() < 1e-9, "{fs}");
        assert!(s.columns.iter().all(|c| c.numeric));
        let s = sniff_text("run.csv", "t,x,y\n0,1,2\n1,3,4\n2,5,6\n").unwrap();
        assert_eq!(s.read, Some(read(",", 1)));
    }

    #[test]
    fn the_skeleton_is_valid_toml_listing_every_file() {
        let a = sniff_text("0A.txt", DAQ).unwrap();
        let b = sniff_text("y.csv", "time;x\n0;1\n0.5;2\n1.0;3\n").unwrap();
        let skipped = [Skipped {
            file: "notes.pdf".into(),
            why: "not text".into(),
        }];
        let mut a2 = a.clone();
        a2.file = "1A.txt".into();
        let text = skeleton("lab", &[a, a2, b], &skipped);
        let v: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(v["sample_rate_hz"].as_float(), Some(1000.0));
        assert_eq!(v["read"]["header_line"].as_integer(), Some(7));
        let tests = v["test"].as_array().unwrap();
        assert_eq!(tests.len(), 3);
        assert!(tests[0].get("read").is_none());
        assert_eq!(tests[2]["read"]["delimiter"].as_str(), Some(";"));
        // a file at another rate than the campaign's gets its own
        assert_eq!(tests[2]["sample_rate_hz"].as_float(), Some(2.0));
        assert!(tests[0].get("sample_rate_hz").is_none());
        assert!(text.contains("# skipped notes.pdf: not text"));
        assert!(text.contains("\"CHANNEL0\": -0.0209, -0.0221, -0.0221"));
    }
}
