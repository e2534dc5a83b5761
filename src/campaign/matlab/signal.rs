//! A campaign `column` resolved in a MAT-file, and the listing of every addressable signal.
//!
//! A `column` is, tried in this order:
//! 1. a variable, or a field of a 1x1 struct as a dotted path (`accel`, `rec.X.Data`),
//!    holding a vector;
//! 2. `name:k`, column `k` (1-based) of a matrix `name` (a vector is its own column 1);
//! 3. a signal of a dSPACE ControlDesk recording (a 1x1 struct with `X` = time struct and
//!    `Y` = struct array of signals with `Name`, `Path`, `Data`) by its `Name`, by its block
//!    path `Path/Name`, or by `Path` alone when that already ends with the name.

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
    /// The time vector `X.Data` of dSPACE recording `recording`.
    DspaceTime { recording: String },
    /// A signal `Y(i)` of a dSPACE recording: its block path (`Path/Name`) and `Unit`.
    DspaceSignal {
        recording: String,
        path: String,
        unit: Option<String>,
    },
}

/// One element of a dSPACE recording's `Y`.
struct DspaceSignal<'a> {
    recording: &'a str,
    name: &'a str,
    path: &'a str,
    unit: Option<&'a str>,
    data: &'a MatValue,
}

impl DspaceSignal<'_> {
    /// `Path/Name`, or the name alone when `Path` is empty.
    fn block_path(&self) -> String {
        match self.path {
            "" => self.name.to_string(),
            p => format!("{p}/{}", self.name),
        }
    }

    fn answers_to(&self, column: &str) -> bool {
        column == self.name
            || column == self.block_path()
            || (!self.path.is_empty() && column == self.path)
    }
}

impl MatFile {
    /// The samples of `column` (see the module doc for the forms it takes).
    pub fn signal(&self, column: &str) -> Result<Vec<f64>, MatError> {
        if let Some(value) = self.lookup(column) {
            return self.vector(column, value);
        }
        if let Some((base, k)) = column.rsplit_once(':') {
            if let (Some(value), Ok(k)) = (self.lookup(base), k.parse::<usize>()) {
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
            if let Some(time) = dspace_time(value) {
                out.push(SignalInfo {
                    column: format!("{name}.X.Data"),
                    len: numel(time),
                    kind: SignalKind::DspaceTime {
                        recording: name.clone(),
                    },
                });
                for s in dspace.iter().filter(|s| s.recording == name) {
                    out.push(dspace_info(s, &dspace));
                }
            } else {
                list_value(name, value, 0, &mut out);
            }
        }
        out
    }

    /// A variable, or a field of 1x1 structs by dotted path.
    fn lookup(&self, path: &str) -> Option<&MatValue> {
        let mut parts = path.split('.');
        let first = self.variable(parts.next()?)?;
        parts.try_fold(first, |value, field| value.field(field))
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
            MatValue::Struct { .. } if dspace_time(value).is_some() => {
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

    /// Every signal of every dSPACE recording, in file order.
    fn dspace_signals(&self) -> Vec<DspaceSignal<'_>> {
        let mut out = Vec::new();
        for (recording, value) in &self.variables {
            let Some(MatValue::Struct {
                fields, elements, ..
            }) = value.field("Y").filter(|_| dspace_time(value).is_some())
            else {
                continue;
            };
            for element in elements {
                let field = |name: &str| {
                    fields
                        .iter()
                        .position(|f| f == name)
                        .and_then(|i| element.get(i))
                };
                let (Some(name), Some(data)) =
                    (field("Name").and_then(MatValue::text), field("Data"))
                else {
                    continue;
                };
                let path = field("Path").and_then(MatValue::text).unwrap_or("");
                let unit = field("Unit").and_then(MatValue::text);
                out.push(DspaceSignal {
                    recording,
                    name,
                    path,
                    unit,
                    data,
                });
            }
        }
        out
    }
}

/// The time vector of a dSPACE recording: `X.Data` of a 1x1 struct that also has `Y`.
fn dspace_time(value: &MatValue) -> Option<&MatValue> {
    value.field("Y")?;
    value.field("X")?.field("Data")
}

/// A dSPACE signal's listing: by name when no other signal has that name, else by block path.
fn dspace_info(s: &DspaceSignal, all: &[DspaceSignal]) -> SignalInfo {
    let unique = all.iter().filter(|o| o.answers_to(s.name)).count() == 1;
    SignalInfo {
        column: if unique {
            s.name.to_string()
        } else {
            s.block_path()
        },
        len: numel(s.data),
        kind: SignalKind::DspaceSignal {
            recording: s.recording.to_string(),
            path: s.block_path(),
            unit: s.unit.map(str::to_string),
        },
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

fn numel(value: &MatValue) -> usize {
    match value {
        MatValue::Numeric { data, .. } => data.len(),
        _ => 0,
    }
}
