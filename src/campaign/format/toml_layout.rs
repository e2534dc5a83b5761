//! campaign.toml's keys for reading a laboratory's files in place: `[read]`, `[columns]`
//! and their per-test overrides `read = {...}`, `columns = {...}` (campaign-format.md,
//! "campaign.toml additions"). Unknown keys inside them are errors: a typo such as
//! `scal = 0.01` would silently read volts as metres.

use super::layout::{ColumnEntry, Decimal, Delimiter, ReadOverride};
use super::toml_values::{as_number, type_name, Lines};
use super::CampaignError;
use std::collections::BTreeMap;

const READ_KEYS: [&str; 4] = ["delimiter", "header_line", "comment", "decimal"];
const COLUMN_KEYS: [&str; 3] = ["column", "scale", "offset"];
/// A header below this line is not a header but a mistake (a data row number): real
/// acquisition software writes at most a few dozen lines of preamble.
const MAX_HEADER_LINE: i64 = 10_000;

/// Where an error points: the value's offset, the test and the key.
struct At<'a> {
    lines: &'a Lines<'a>,
    offset: usize,
    test: Option<&'a str>,
}

impl At<'_> {
    fn err(&self, key: &str, message: impl Into<String>) -> CampaignError {
        self.lines
            .err(Some(self.offset), self.test, Some(key), message)
    }
}

fn table<'v>(
    at: &At,
    key: &str,
    v: &'v toml::Value,
    example: &str,
) -> Result<&'v toml::Table, CampaignError> {
    match v {
        toml::Value::Table(t) => Ok(t),
        other => Err(at.err(
            key,
            format!(
                "expected a table like {example}, found {}",
                type_name(other)
            ),
        )),
    }
}

/// `[read]` or a test's `read = {...}`.
pub(super) fn read_options(
    lines: &Lines,
    offset: usize,
    test: Option<&str>,
    v: &toml::Value,
) -> Result<ReadOverride, CampaignError> {
    let at = At {
        lines,
        offset,
        test,
    };
    let t = table(&at, "read", v, "{ header_line = 7 }")?;
    let mut o = ReadOverride::default();
    for (k, val) in t {
        let key = format!("read.{k}");
        match (k.as_str(), val) {
            ("delimiter", toml::Value::String(s)) => o.delimiter = Some(delimiter(&at, &key, s)?),
            ("header_line", toml::Value::Integer(i)) if (0..=MAX_HEADER_LINE).contains(i) => {
                o.header_line = Some(*i as usize)
            }
            ("header_line", other) => {
                return Err(at.err(&key, format!(
                    "expected the 1-based line of the column names (0: no header line, at most {MAX_HEADER_LINE}), found {}",
                    shown(other)
                )))
            }
            ("comment", toml::Value::String(s)) => o.comment = Some(s.clone()),
            ("decimal", toml::Value::String(s)) => {
                o.decimal = Some(match s.as_str() {
                    "." => Decimal::Point,
                    "," => Decimal::Comma,
                    _ => {
                        return Err(at.err(&key, format!(
                            "`{s}` is not a decimal separator: \".\" or \",\""
                        )))
                    }
                })
            }
            (k, other) if READ_KEYS.contains(&k) => {
                return Err(at.err(&key, format!("expected a string, found {}", type_name(other))))
            }
            _ => {
                return Err(at.err(&key, format!(
                    "unknown key; [read] has {}",
                    READ_KEYS.join(", ")
                )))
            }
        }
    }
    Ok(o)
}

fn shown(v: &toml::Value) -> String {
    match v {
        toml::Value::Integer(i) => i.to_string(),
        other => type_name(other).to_string(),
    }
}

fn delimiter(at: &At, key: &str, s: &str) -> Result<Delimiter, CampaignError> {
    let mut chars = s.chars();
    match (s, chars.next(), chars.next()) {
        ("whitespace", _, _) => Ok(Delimiter::Whitespace),
        (_, Some(c), None) if c != '"' && !c.is_alphanumeric() && c != '.' && c != '-' => {
            Ok(Delimiter::Char(c))
        }
        _ => Err(at.err(
            key,
            format!("`{s}` is not a delimiter: \",\", \";\", \"\\t\", \"whitespace\" or another single separator character"),
        )),
    }
}

/// `[columns]` or a test's `columns = {...}`: channel = `{ column, scale, offset }` or a
/// bare column name.
pub(super) fn columns(
    lines: &Lines,
    offset: usize,
    test: Option<&str>,
    v: &toml::Value,
) -> Result<BTreeMap<String, ColumnEntry>, CampaignError> {
    let at = At {
        lines,
        offset,
        test,
    };
    let t = table(
        &at,
        "columns",
        v,
        "{ force_n = { column = \"CH1\", scale = 9806.65 } }",
    )?;
    let mut out = BTreeMap::new();
    for (channel, val) in t {
        let key = format!("columns.{channel}");
        let entry = match val {
            toml::Value::String(_) | toml::Value::Integer(_) => ColumnEntry {
                column: Some(column_name(&at, &key, val)?),
                ..ColumnEntry::default()
            },
            toml::Value::Table(e) => column_entry(&at, &key, e)?,
            toml::Value::Boolean(false) if test.is_some() => ColumnEntry {
                unmapped: true,
                ..ColumnEntry::default()
            },
            other => {
                return Err(at.err(&key, format!(
                    "expected {{ column = ..., scale = ..., offset = ... }}, a column name or (in a test) false, found {}",
                    type_name(other)
                )))
            }
        };
        out.insert(channel.clone(), entry);
    }
    Ok(out)
}

fn column_entry(at: &At, key: &str, e: &toml::Table) -> Result<ColumnEntry, CampaignError> {
    let mut c = ColumnEntry::default();
    for (k, val) in e {
        let key = format!("{key}.{k}");
        match k.as_str() {
            "column" => c.column = Some(column_name(at, &key, val)?),
            "scale" => {
                let s = finite(at, &key, val)?;
                if s == 0.0 {
                    return Err(at.err(&key, "a scale of 0 would erase the channel"));
                }
                c.scale = Some(s);
            }
            "offset" => c.offset = Some(finite(at, &key, val)?),
            _ => {
                return Err(at.err(
                    &key,
                    format!(
                        "unknown key; a column mapping has {}",
                        COLUMN_KEYS.join(", ")
                    ),
                ))
            }
        }
    }
    Ok(c)
}

/// A column by name, or by 1-based number for a file without a header line.
fn column_name(at: &At, key: &str, v: &toml::Value) -> Result<String, CampaignError> {
    match v {
        toml::Value::String(s) if !s.trim().is_empty() => Ok(s.trim().to_string()),
        toml::Value::Integer(i) if *i >= 1 => Ok(i.to_string()),
        other => Err(at.err(
            key,
            format!(
                "expected a column name or a 1-based column number, found {}",
                shown(other)
            ),
        )),
    }
}

fn finite(at: &At, key: &str, v: &toml::Value) -> Result<f64, CampaignError> {
    match as_number(v) {
        Some(x) if x.is_finite() => Ok(x),
        Some(x) => Err(at.err(key, format!("{x} is not a finite number"))),
        None => Err(at.err(key, format!("expected a number, found {}", type_name(v)))),
    }
}
