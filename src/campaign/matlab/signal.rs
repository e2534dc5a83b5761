//! A campaign `column` resolved in a MAT-file, and the listing of every addressable signal.
//!
//! A `column` is, tried in this order:
//! 1. a variable, or a struct field as a dotted path with 1-based element indices where
//!    a struct is an array (`accel`, `rec.X.Data`, `rec.Y(2).Data`), holding a vector;
//! 2. `name:k`, column `k` (1-based) of a matrix `name` (a vector is its own column 1);
//! 3. a signal of a dSPACE ControlDesk recording (a 1x1 struct with `X` = time struct and
//!    `Y` = struct array of signals with `Name`, `Path`, `Data`) by its `Name`, by its block
//!    path `Path/Name`, or by `Path` alone when that already ends with the name.
//!
//! A recording's time is `rec.X.Data` (`rec.X(k).Data` when it has several time bases; a
//! signal's own is `X(XIndex)` when `Y(i).XIndex` is given, else `X(1)`).

use super::dspace::{dspace_info, dspace_times, is_recording, DspaceSignal};
use super::{MatError, MatFile, MatValue};

/// How many names an unknown-column error lists.
const NAMES_LISTED: usize = 20;
/// Deepest dotted path listed by [`MatFile::signals`] (`a.b.c.d`).
const MAX_LISTED_DEPTH: usize = 4;

/// One addressable signal: the `column` that reads it and its number of samples.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalInfo {
    pub column: String,
    pub len: usize,
    pub kind: SignalKind,
}

#[derive(Debug, Clone, PartialEq)]
pub enum SignalKind {
    /// A vector variable or a vector field of a struct (dotted path).
    Variable,
    /// Column `k` of a matrix (`name:k`).
    MatrixColumn,
    /// A time vector `X(k).Data` of dSPACE recording `recording`.
    DspaceTime { recording: String },
    /// A signal `Y(i)` of a dSPACE recording: its block path (`Path/Name`), `Unit`, and
    /// the column of its time vector.
    DspaceSignal {
        recording: String,
        path: String,
        unit: Option<String>,
        time: String,
    },
}

impl MatFile {
    /// The samples of `column` (see the module doc for the forms it takes).
    pub fn signal(&self, column: &str) -> Result<Vec<f64>, MatError> {
        if let Some(value) = self.value_at(column) {
            return self.vector(column, value);
        }
        if let Some((base, k)) = column.rsplit_once(':') {
            if let (Some(value), Ok(k)) = (self.value_at(base), k.parse::<usize>()) {
                return self.matrix_column(column, value, k);
            }
        }
        self.dspace_signal(column)
    }

    /// Every addressable signal in file order: vectors, matrix columns, dSPACE time and signals.
    pub fn signals(&self) -> Vec<SignalInfo> {
        let dspace = self.dspace_signals();
        let mut out = Vec::new();
        for (name, value) in &self.variables {
            let times = dspace_times(name, value);
            if times.is_empty() {
                list_value(name, value, 0, &mut out);
                continue;
            }
            for (column, time) in times {
                let recording = name.clone();
                let kind = SignalKind::DspaceTime { recording };
                out.push(SignalInfo {
                    column,
                    len: numel(time),
                    kind,
                });
            }
            for s in dspace.iter().filter(|s| s.recording == name) {
                out.push(dspace_info(s, &dspace));
            }
        }
        out
    }

    /// A variable, or a struct field by dotted path with 1-based element indices
    /// (`rec.Y(2).Data`, `rec.Description`).
    pub fn value_at(&self, path: &str) -> Option<&MatValue> {
        let mut parts = path.split('.');
        let (name, mut index) = split_index(parts.next()?)?;
        let mut value = self.variable(name)?;
        for part in parts {
            let (field, next) = split_index(part)?;
            value = struct_field(value, index, field)?;
            index = next;
        }
        index.is_none().then_some(value)
    }

    fn not_a_signal(&self, column: &str, why: String) -> MatError {
        MatError::NotASignal {
            file: self.file.clone(),
            column: column.to_string(),
            why,
        }
    }

    /// The samples of a vector value; anything else is refused with what it is.
    fn vector(&self, column: &str, value: &MatValue) -> Result<Vec<f64>, MatError> {
        let why = match value {
            MatValue::Numeric { data, .. } if data.is_empty() => {
                format!("is empty ({})", value.describe())
            }
            MatValue::Numeric { dims, data } if is_vector(dims) => return Ok(data.clone()),
            MatValue::Numeric { dims, .. } if dims.len() == 2 => {
                format!(
                    "is a {}; name one of its columns, `{column}:1` to `{column}:{}`",
                    value.describe(),
                    dims[1]
                )
            }
            MatValue::Struct { .. } if is_recording(value) => {
                format!(
                    "is a dSPACE recording; name one of its signals ({})",
                    self.listing()
                )
            }
            MatValue::Struct { fields, .. } => {
                format!(
                    "is a {} with fields {}; name one as `{column}.{}`",
                    value.describe(),
                    fields.join(", "),
                    fields.first().map_or("field", |f| f)
                )
            }
            MatValue::Char(text) => format!(
                "is text (\"{}\"), not samples",
                text.chars().take(40).collect::<String>()
            ),
            MatValue::Numeric { .. } => {
                format!(
                    "is a {}, neither a vector nor a 2-D matrix",
                    value.describe()
                )
            }
            other => format!(
                "is a {}, not a vector of samples; save it as a real double array",
                other.describe()
            ),
        };
        Err(self.not_a_signal(column, why))
    }

    /// Column `k` (1-based) of a 2-D numeric value.
    fn matrix_column(
        &self,
        column: &str,
        value: &MatValue,
        k: usize,
    ) -> Result<Vec<f64>, MatError> {
        let MatValue::Numeric { dims, data } = value else {
            return Err(self.not_a_signal(
                column,
                format!("is a {}, which has no columns", value.describe()),
            ));
        };
        if dims.len() != 2 {
            return Err(self.not_a_signal(
                column,
                format!("is a {}, not a 2-D matrix", value.describe()),
            ));
        }
        let (rows, cols) = if dims[0] == 1 {
            (dims[1], 1)
        } else {
            (dims[0], dims[1])
        };
        if k == 0 || k > cols {
            return Err(self.not_a_signal(
                column,
                format!(
                    "column {k} of a {} (columns are 1 to {cols})",
                    value.describe()
                ),
            ));
        }
        match data.get((k - 1) * rows..k * rows) {
            Some(samples) => Ok(samples.to_vec()),
            None => Err(self.not_a_signal(
                column,
                format!("holds {} values, too few for its dimensions", data.len()),
            )),
        }
    }

    /// The dSPACE signal that `column` names, by name or block path.
    fn dspace_signal(&self, column: &str) -> Result<Vec<f64>, MatError> {
        let all = self.dspace_signals();
        let matches: Vec<&DspaceSignal> = all.iter().filter(|s| s.answers_to(column)).collect();
        match matches.as_slice() {
            [one] => self.vector(column, one.data),
            [] => Err(MatError::UnknownColumn {
                file: self.file.clone(),
                column: column.to_string(),
                available: self.listing(),
            }),
            many => Err(MatError::Ambiguous {
                file: self.file.clone(),
                column: column.to_string(),
                count: many.len(),
                paths: many
                    .iter()
                    .map(|s| format!("\"{}\"", s.block_path()))
                    .collect::<Vec<_>>()
                    .join(", "),
            }),
        }
    }

    /// The first [`NAMES_LISTED`] columns of [`Self::signals`], for messages.
    fn listing(&self) -> String {
        let all = self.signals();
        let mut names: Vec<String> = all
            .iter()
            .take(NAMES_LISTED)
            .map(|s| format!("`{}`", s.column))
            .collect();
        if all.len() > NAMES_LISTED {
            names.push(format!("and {} more", all.len() - NAMES_LISTED));
        }
        if names.is_empty() {
            return "no numeric vector".into();
        }
        names.join(", ")
    }
}

/// Field `field` of element `index` (1-based; `None` for a 1x1 struct) of a struct.
pub(super) fn struct_field<'a>(
    value: &'a MatValue,
    index: Option<usize>,
    field: &str,
) -> Option<&'a MatValue> {
    let MatValue::Struct {
        fields, elements, ..
    } = value
    else {
        return None;
    };
    let element = match index {
        Some(k) => elements.get(k.checked_sub(1)?)?,
        None if elements.len() == 1 => &elements[0],
        None => return None,
    };
    element.get(fields.iter().position(|f| f == field)?)
}

/// `name(k)` as `(name, Some(k))`, `name` as `(name, None)`; `None` for a bad index.
fn split_index(part: &str) -> Option<(&str, Option<usize>)> {
    match part.strip_suffix(')').and_then(|p| p.split_once('(')) {
        Some((name, k)) => Some((name, Some(k.parse().ok()?))),
        None => Some((part, None)),
    }
}

/// List the vectors, matrix columns and (through 1x1 structs) fields of `value` as `column`.
fn list_value(column: &str, value: &MatValue, depth: usize, out: &mut Vec<SignalInfo>) {
    match value {
        MatValue::Numeric { dims, data } if !data.is_empty() && is_vector(dims) => {
            out.push(SignalInfo {
                column: column.to_string(),
                len: data.len(),
                kind: SignalKind::Variable,
            });
        }
        MatValue::Numeric { dims, data } if !data.is_empty() && dims.len() == 2 => {
            for k in 1..=dims[1] {
                let column = format!("{column}:{k}");
                out.push(SignalInfo {
                    column,
                    len: dims[0],
                    kind: SignalKind::MatrixColumn,
                });
            }
        }
        MatValue::Struct {
            fields, elements, ..
        } if elements.len() == 1 && depth < MAX_LISTED_DEPTH => {
            for (field, v) in fields.iter().zip(&elements[0]) {
                list_value(&format!("{column}.{field}"), v, depth + 1, out);
            }
        }
        _ => {}
    }
}

/// A numeric array with at most one dimension above 1.
fn is_vector(dims: &[usize]) -> bool {
    dims.iter().filter(|&&d| d > 1).count() <= 1
}

pub(super) fn numel(value: &MatValue) -> usize {
    match value {
        MatValue::Numeric { data, .. } => data.len(),
        _ => 0,
    }
}
