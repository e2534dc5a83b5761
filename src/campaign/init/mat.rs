//! `campaign init` for a MATLAB file (campaign-format.md, "MATLAB files"): every
//! addressable signal as the `column` that reads it (a variable, `matrix:k`, a dSPACE
//! signal by name or block path) with its first samples, the variables that are no
//! signal, and a rate from a dSPACE time vector, a time variable or a rate variable.

use super::{is_time_name, median_step_rate, ColumnSample, Sniffed, MAX_FILE_BYTES, SAMPLE_VALUES};
use crate::campaign::files::read_regular;
use crate::campaign::matlab::{read_mat, MatFile, MatValue, SignalInfo, SignalKind};
use std::fmt::Write as _;
use std::path::Path;

/// Significant digits of a sample shown in the skeleton (enough to see a scale and sign).
const SAMPLE_DIGITS: usize = 6;
/// Characters of a text variable shown beside it.
const TEXT_SHOWN: usize = 40;

/// Read MATLAB file `path` (named `name`) and describe it; Err: why it is skipped.
pub(super) fn sniff_mat_file(path: &Path, name: &str) -> Result<Sniffed, String> {
    let bytes = read_regular(path, MAX_FILE_BYTES, "largest plausible record")
        .map_err(|r| r.to_string())?;
    let mat = read_mat(&bytes, name).map_err(|e| {
        let e = e.to_string();
        // the skipped list names the file already
        e.strip_prefix(&format!("{name}: "))
            .unwrap_or(&e)
            .to_string()
    })?;
    sniff_mat(&mat)
}

/// What a MATLAB file read into `mat` holds; Err when it holds no signal.
pub(super) fn sniff_mat(mat: &MatFile) -> Result<Sniffed, String> {
    let signals = mat.signals();
    if signals.is_empty() {
        let vars: Vec<String> = mat
            .variables
            .iter()
            .map(|(n, v)| format!("`{n}` ({})", v.describe()))
            .collect();
        return Err(format!(
            "a MATLAB file without a numeric vector or matrix to read (its variables: {})",
            if vars.is_empty() {
                "none".to_string()
            } else {
                vars.join(", ")
            }
        ));
    }
    let mut columns: Vec<ColumnSample> = signals.iter().map(|s| sample(mat, s)).collect();
    columns.extend(other_variables(mat, &signals));
    Ok(Sniffed {
        file: mat.file.clone(),
        read: None,
        columns,
        sample_rate: rate(mat, &signals),
    })
}

/// One signal with its first samples and what it is.
fn sample(mat: &MatFile, s: &SignalInfo) -> ColumnSample {
    let values = mat
        .signal(&s.column)
        .map(|x| x.iter().take(SAMPLE_VALUES).map(|v| shown(*v)).collect())
        .unwrap_or_default();
    let samples = format!("{} samples", s.len);
    let note = match &s.kind {
        SignalKind::Variable => samples,
        SignalKind::MatrixColumn => {
            let base = s.column.rsplit_once(':').map_or("", |(b, _)| b);
            let what = mat
                .value_at(base)
                .map_or_else(|| "matrix".to_string(), MatValue::describe);
            format!("{samples}, a column of `{base}`, {what}")
        }
        SignalKind::DspaceTime { recording } => {
            format!("{samples}, the time of dSPACE recording `{recording}`")
        }
        SignalKind::DspaceSignal {
            path, unit, time, ..
        } => {
            let unit = unit.as_ref().map_or(String::new(), |u| format!(", {u}"));
            format!("{samples}, dSPACE signal \"{path}\"{unit}, time `{time}`")
        }
    };
    ColumnSample {
        name: s.column.clone(),
        values,
        numeric: true,
        note,
    }
}

/// The top-level variables no signal reads (text, cells, complex or sparse arrays), listed
/// as not numeric so that the user sees them and why they cannot be mapped.
fn other_variables(mat: &MatFile, signals: &[SignalInfo]) -> Vec<ColumnSample> {
    let read_by_a_signal = |name: &str| {
        signals.iter().any(|s| {
            let c = &s.column;
            c == name || c.starts_with(&format!("{name}:")) || c.starts_with(&format!("{name}."))
        }) || signals.iter().any(|s| match &s.kind {
            SignalKind::DspaceTime { recording } | SignalKind::DspaceSignal { recording, .. } => {
                recording == name
            }
            _ => false,
        })
    };
    mat.variables
        .iter()
        .filter(|(name, _)| !read_by_a_signal(name))
        .map(|(name, value)| {
            let note = match value {
                MatValue::Char(text) => format!(
                    "not a signal: text \"{}\"",
                    text.chars().take(TEXT_SHOWN).collect::<String>()
                ),
                other => format!("not a signal: {}", other.describe()),
            };
            ColumnSample {
                name: name.clone(),
                values: Vec::new(),
                numeric: false,
                note,
            }
        })
        .collect()
}

/// A rate from the file: a dSPACE time vector's median step, else a vector named like time
/// (seconds assumed), else a scalar named like a rate (`fs`) or a step (`dt`).
fn rate(mat: &MatFile, signals: &[SignalInfo]) -> Option<(f64, String)> {
    let steps_of = |s: &SignalInfo| {
        mat.signal(&s.column)
            .ok()
            .and_then(|t| median_step_rate(&t))
    };
    let dspace = signals
        .iter()
        .filter(|s| matches!(s.kind, SignalKind::DspaceTime { .. }));
    let named_time = signals.iter().filter(|s| {
        s.kind == SignalKind::Variable && s.len > 1 && is_time_name(last_name(&s.column))
    });
    if let Some((s, fs)) = dspace
        .chain(named_time)
        .find_map(|s| steps_of(s).map(|fs| (s, fs)))
    {
        let from = match s.kind {
            SignalKind::DspaceTime { .. } => {
                format!("the median step of dSPACE time `{}`", s.column)
            }
            _ => format!(
                "the median step of `{}`, read as seconds (set its scale if it is not)",
                s.column
            ),
        };
        return Some((fs, from));
    }
    signals
        .iter()
        .filter(|s| s.kind == SignalKind::Variable && s.len == 1)
        .find_map(|s| {
            let v = *mat.signal(&s.column).ok()?.first()?;
            let fs = match rate_variable(last_name(&s.column))? {
                RateVariable::Rate => v,
                RateVariable::Step => 1.0 / v,
            };
            (fs.is_finite() && fs > 0.0)
                .then(|| (fs, format!("the variable `{}` = {}", s.column, shown(v))))
        })
}

enum RateVariable {
    Rate,
    Step,
}

/// Whether a scalar's name says it is a sample rate (`fs`, `sample_rate`) or step (`dt`).
fn rate_variable(name: &str) -> Option<RateVariable> {
    let n = name.to_ascii_lowercase().replace('_', "");
    match n.as_str() {
        "fs" | "samplerate" | "samplingrate" | "sampleratehz" | "srate" => Some(RateVariable::Rate),
        "dt" | "ts" | "sampletime" | "samplinginterval" | "sampleinterval" => {
            Some(RateVariable::Step)
        }
        _ => None,
    }
}

/// The last part of a dotted column (`rec.t` -> `t`).
fn last_name(column: &str) -> &str {
    column.rsplit('.').next().unwrap_or(column)
}

/// A sample to [`SAMPLE_DIGITS`] significant digits.
fn shown(x: f64) -> String {
    // + 0.0 shows -0 as 0
    format!("{x:.*e}", SAMPLE_DIGITS - 1)
        .parse::<f64>()
        .map_or_else(|_| x.to_string(), |r| (r + 0.0).to_string())
}

/// The comment lines of a MATLAB file's `[[test]]` entry: how to map it, then every signal
/// and every other variable.
pub(super) fn listing(f: &Sniffed) -> String {
    let mut s = String::new();
    let time = f.columns.iter().find(|c| {
        c.note.contains("the time of dSPACE") || (c.numeric && is_time_name(last_name(&c.name)))
    });
    let time_key = time.map_or(String::new(), |c| {
        format!("time_s = {}, ", toml::Value::String(c.name.clone()))
    });
    let _ = writeln!(
        s,
        "# columns = {{ {time_key}displacement_m = {{ column = \"...\", scale = 1.0 }} }}   # FILL IN: this file's own mapping"
    );
    let _ = writeln!(
        s,
        "# signals of {} (a `column` names a variable, `matrix:k` for column k of a matrix, a dSPACE signal by its name or block path):",
        f.file
    );
    for c in &f.columns {
        if c.numeric {
            let _ = writeln!(s, "#   {:?} ({}): {}", c.name, c.note, c.values.join(", "));
        } else {
            let _ = writeln!(s, "#   {:?} ({})", c.name, c.note);
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture(name: &str) -> MatFile {
        let path = format!("{}/tests/data/matlab/{name}", env!("CARGO_MANIFEST_DIR"));
        read_mat(&std::fs::read(path).unwrap(), name).unwrap()
    }

    #[test]
    fn a_plain_file_lists_variables_and_matrix_columns() {
        let s = sniff_mat(&fixture("plain.mat")).unwrap();
        let names: Vec<&str> = s.columns.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            ["accel", "data:1", "data:2", "data:3", "counts", "label", "notes", "z", "sp"]
        );
        assert_eq!(s.columns[1].values, ["100.25", "101.25", "102.25"]);
        assert!(
            s.columns[1].note.contains("a column of `data`, 50x3"),
            "{:?}",
            s.columns[1]
        );
        assert!(!s.columns[5].numeric && s.columns[5].note.contains("Xgf table displacement"));
        assert_eq!(s.read, None);
        assert_eq!(s.sample_rate, None, "no time and no rate in the file");
    }

    #[test]
    fn a_dspace_recording_lists_signals_and_gives_its_rate() {
        let s = sniff_mat(&fixture("dspace.mat")).unwrap();
        let (fs, from) = s.sample_rate.clone().unwrap();
        assert_eq!(fs, 1000.0);
        assert!(from.contains("`rec.X.Data`"), "{from}");
        let agf = s.columns.iter().find(|c| c.name == "Agf").unwrap();
        assert!(
            agf.note
                .contains("dSPACE signal \"Model Root/Plant/Agf\", m/s^2, time `rec.X.Data`"),
            "{}",
            agf.note
        );
        assert_eq!(agf.values, ["0", "0.5", "1"]);
        let text = listing(&s);
        assert!(
            text.contains("# columns = { time_s = \"rec.X.Data\", "),
            "{text}"
        );
        assert!(text.contains("\"Model Root/Controller/Xgf\" ("), "{text}");
    }

    #[test]
    fn rate_and_step_variables() {
        assert!(matches!(rate_variable("Fs"), Some(RateVariable::Rate)));
        assert!(matches!(
            rate_variable("sample_rate"),
            Some(RateVariable::Rate)
        ));
        assert!(matches!(rate_variable("dt"), Some(RateVariable::Step)));
        assert!(rate_variable("accel").is_none());
    }
}
