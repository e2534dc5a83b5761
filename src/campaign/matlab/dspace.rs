//! dSPACE ControlDesk recordings: a 1x1 struct with `X` = time bases (`X(k).Data`) and
//! `Y` = signals (`Y(i).Name`, `.Path`, `.Data`, often `.Unit`, `.XIndex`).

use super::signal::{numel, struct_field, SignalInfo, SignalKind};
use super::{MatFile, MatValue};

/// One element of a dSPACE recording's `Y`.
pub(super) struct DspaceSignal<'a> {
    pub(super) recording: &'a str,
    name: &'a str,
    path: &'a str,
    unit: Option<&'a str>,
    pub(super) data: &'a MatValue,
    /// The column of its time vector, `rec.X.Data` or `rec.X(k).Data`.
    time: String,
}

impl DspaceSignal<'_> {
    /// `Path/Name`, or the name alone when `Path` is empty.
    pub(super) fn block_path(&self) -> String {
        match self.path {
            "" => self.name.to_string(),
            p => format!("{p}/{}", self.name),
        }
    }

    pub(super) fn answers_to(&self, column: &str) -> bool {
        column == self.name
            || column == self.block_path()
            || (!self.path.is_empty() && column == self.path)
    }
}

impl MatFile {
    /// Every signal of every dSPACE recording, in file order.
    pub(super) fn dspace_signals(&self) -> Vec<DspaceSignal<'_>> {
        let mut out = Vec::new();
        for (recording, value) in &self.variables {
            let times = dspace_times(recording, value);
            let Some(MatValue::Struct {
                fields, elements, ..
            }) = value.field("Y").filter(|_| !times.is_empty())
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
                let x_index = match field("XIndex") {
                    Some(MatValue::Numeric { data, .. }) if data.len() == 1 => data[0] as usize,
                    _ => 1,
                };
                let time = times
                    .get(x_index.wrapping_sub(1))
                    .unwrap_or(&times[0])
                    .0
                    .clone();
                out.push(DspaceSignal {
                    recording,
                    name,
                    path,
                    unit,
                    data,
                    time,
                });
            }
        }
        out
    }
}

/// The time vectors of a dSPACE recording `name` (a 1x1 struct with `Y` and `X(k).Data`)
/// with their columns; empty when `value` is not a recording.
pub(super) fn dspace_times<'a>(name: &str, value: &'a MatValue) -> Vec<(String, &'a MatValue)> {
    let (Some(MatValue::Struct { .. }), Some(x @ MatValue::Struct { elements, .. })) =
        (value.field("Y"), value.field("X"))
    else {
        return Vec::new();
    };
    let n = elements.len();
    (1..=n)
        .filter_map(|k| {
            let column = match n {
                1 => format!("{name}.X.Data"),
                _ => format!("{name}.X({k}).Data"),
            };
            Some((column, struct_field(x, Some(k), "Data")?))
        })
        .collect()
}

pub(super) fn is_recording(value: &MatValue) -> bool {
    !dspace_times("", value).is_empty()
}

/// A dSPACE signal's listing: by name when no other signal has that name, else by block path.
pub(super) fn dspace_info(s: &DspaceSignal, all: &[DspaceSignal]) -> SignalInfo {
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
            time: s.time.clone(),
        },
    }
}
