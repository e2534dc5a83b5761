//! Ground motions as laboratories get them: a PEER NGA `.AT2` file, or a text file of one
//! column (acceleration, with a step given by the user), two columns (time, acceleration)
//! or named columns (a campaign CSV: `time_s` and a channel such as `acceleration_m_s2`).

use super::{MotionError, STANDARD_GRAVITY_M_S2};
use crate::campaign::files::{decode_utf8, lines_any, read_regular};
use crate::campaign::format::Decimal;
use std::path::Path;

/// Largest ground-motion file read: 100 MB holds about 10 million samples as text, hours
/// of a 1 kHz record; anything larger is not a ground motion.
pub const MAX_MOTION_BYTES: u64 = 100 << 20;

/// Largest time step accepted, s: strong-motion records are sampled at 50 Hz or faster;
/// a step of a second or more is a wrong unit (ms given as s) rather than a record.
pub const MAX_STEP_S: f64 = 0.5;

/// Smallest time step accepted, s (100 kHz): faster than any accelerograph or controller.
pub const MIN_STEP_S: f64 = 1e-5;

/// Fewest samples of a ground motion: below this there is no motion to reproduce.
pub const MIN_SAMPLES: usize = 16;

/// A time column may deviate from a uniform grid by this fraction of the step (lab files
/// round their times, e.g. 1/1024 s printed to 4 decimals is off by up to 5 %); beyond it
/// the record is not uniformly sampled and is refused rather than silently re-timed.
pub const TIME_ROUNDING_TOLERANCE: f64 = 0.1;

/// Units of an acceleration column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AccelerationUnit {
    StandardGravity,
    MetrePerSecondSquared,
    CentimetrePerSecondSquared,
}

impl AccelerationUnit {
    /// Parse `g`, `m/s2` (`m/s^2`, `m_s2`), `cm/s2` (`gal`).
    pub fn parse(text: &str) -> Option<Self> {
        match text.trim().to_ascii_lowercase().as_str() {
            "g" => Some(Self::StandardGravity),
            "m/s2" | "m/s^2" | "m_s2" | "m/s/s" => Some(Self::MetrePerSecondSquared),
            "cm/s2" | "cm/s^2" | "cm_s2" | "cm/s/s" | "gal" => {
                Some(Self::CentimetrePerSecondSquared)
            }
            _ => None,
        }
    }

    /// Metres per second squared in one unit.
    pub fn to_m_s2(self) -> f64 {
        match self {
            Self::StandardGravity => STANDARD_GRAVITY_M_S2,
            Self::MetrePerSecondSquared => 1.0,
            Self::CentimetrePerSecondSquared => 0.01,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::StandardGravity => "g",
            Self::MetrePerSecondSquared => "m/s^2",
            Self::CentimetrePerSecondSquared => "cm/s^2",
        }
    }
}

/// How to read a file where the file itself does not say.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// The time step, s, for a file without a time column (or to confirm the AT2 header's).
    pub step_s: Option<f64>,
    /// The acceleration's unit, for a file whose header does not give one.
    pub unit: Option<AccelerationUnit>,
    /// The acceleration column: a header name, or a 1-based number.
    pub column: Option<String>,
    /// The file writes decimal commas (`0,0125`). Found without being told where a line
    /// has several cells ([`decimal_of`]); a file of one column of such numbers
    /// reads as two integer columns unless told.
    pub decimal_comma: bool,
}

/// The decimal separator the data lines of `lines` write: a comma when told, or when
/// every line that reads as numbers either way reads with the comma as the decimal
/// point, some line has several cells (a semicolon, tab or space between them, so that a
/// comma cannot be the delimiter) and some cell has a comma; else a point. Under many
/// European locales a DAQ or spreadsheet writes `0,0125;-0,31`. A comma must sit between
/// digits (`0, 1` is a comma-delimited row, not `0.` and `1`).
fn decimal_of(lines: &[&str], told_comma: bool) -> Decimal {
    if told_comma {
        return Decimal::Comma;
    }
    let (mut several, mut comma) = (false, false);
    for line in lines.iter().filter(|l| !is_comment(l)) {
        match numbers_in(line, Decimal::Comma) {
            Some(v) => {
                several |= v.len() > 1;
                comma |= line.contains(',');
            }
            None if numbers_in(line, Decimal::Point).is_some() => return Decimal::Point,
            None => {} // a header line
        }
    }
    match several && comma {
        true => Decimal::Comma,
        false => Decimal::Point,
    }
}

/// A ground motion as read: uniform samples of acceleration, in m/s^2.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundMotion {
    pub step_s: f64,
    pub acceleration_m_s2: Vec<f64>,
    /// What was read: the format, unit, step and where each came from.
    pub source: String,
}

/// Read a ground motion from `path`: `.AT2` by its extension or its header, text otherwise.
pub fn read_motion(path: &Path, options: &ReadOptions) -> Result<GroundMotion, MotionError> {
    let file = path.display().to_string();
    let err = |message: String| MotionError::Read {
        file: file.clone(),
        message,
    };
    let bytes = read_regular(path, MAX_MOTION_BYTES, "largest plausible ground motion")
        .map_err(|r| err(r.to_string()))?;
    let text = decode_utf8(bytes).map_err(|b| err(b.to_string()))?;
    let lines: Vec<&str> = lines_any(&text).collect();
    let is_at2 = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("at2"))
        || lines
            .get(3)
            .is_some_and(|l| l.to_ascii_uppercase().contains("NPTS"));
    let motion = if is_at2 {
        super::at2::read_at2(&lines, &file, options)?
    } else {
        read_columns(&lines, &file, options)?
    };
    check_motion(&motion, &file)?;
    Ok(motion)
}

/// The step and the samples are plausible and finite.
fn check_motion(m: &GroundMotion, file: &str) -> Result<(), MotionError> {
    let err = |message: String| MotionError::Read {
        file: file.to_string(),
        message,
    };
    if !(MIN_STEP_S..=MAX_STEP_S).contains(&m.step_s) {
        return Err(err(format!(
            "time step {} s is outside [{MIN_STEP_S}, {MAX_STEP_S}] s: check the step's unit",
            m.step_s
        )));
    }
    if m.acceleration_m_s2.len() < MIN_SAMPLES {
        return Err(err(format!(
            "{} samples: a ground motion needs at least {MIN_SAMPLES}",
            m.acceleration_m_s2.len()
        )));
    }
    Ok(())
}

/// A line's numbers split on commas, semicolons, tabs or spaces; `None` if a cell is not
/// a number.
pub(super) fn numbers(line: &str) -> Option<Vec<f64>> {
    numbers_in(line, Decimal::Point)
}

/// A line's numbers written with the decimal separator `sep`; `None` if a cell is not a
/// number.
fn numbers_in(line: &str, sep: Decimal) -> Option<Vec<f64>> {
    cells(line, sep).map(|c| number(c, sep)).collect()
}

fn number(cell: &str, sep: Decimal) -> Option<f64> {
    match sep {
        Decimal::Point => cell.parse().ok(),
        Decimal::Comma => {
            let digit = |c: Option<char>| c.is_some_and(|c| c.is_ascii_digit());
            let between_digits = cell.match_indices(',').all(|(k, _)| {
                digit(cell[..k].chars().next_back()) && digit(cell[k + 1..].chars().next())
            });
            let one = cell.matches(',').count() <= 1 && !cell.contains('.');
            (between_digits && one)
                .then(|| cell.replace(',', ".").parse().ok())
                .flatten()
        }
    }
}

fn cells(line: &str, sep: Decimal) -> impl Iterator<Item = &str> {
    let comma_splits = sep == Decimal::Point;
    line.split(move |c: char| (comma_splits && c == ',') || c == ';' || c.is_whitespace())
        .filter(|c| !c.is_empty())
}

fn is_comment(line: &str) -> bool {
    let t = line.trim_start();
    t.is_empty() || t.starts_with('#') || t.starts_with('%') || t.starts_with("//")
}

/// A column file: an optional header line of names, then rows of numbers.
fn read_columns(
    lines: &[&str],
    file: &str,
    options: &ReadOptions,
) -> Result<GroundMotion, MotionError> {
    let lines: Vec<&str> = lines
        .iter()
        .map(|l| l.trim_start_matches('\u{feff}'))
        .collect();
    let sep = decimal_of(&lines, options.decimal_comma);
    let table = ColumnRows::read(&lines, sep, file)?;
    let width = table.width(file)?;
    let layout = ColumnLayout::choose(table.header.as_ref(), width, file, options)?;
    let acceleration = table.acceleration(&layout, file)?;
    let (step_s, step_from) = table.step(layout.time, &lines, sep, file, options)?;
    Ok(GroundMotion {
        step_s,
        source: format!(
            "{file}: column `{}` in {} ({}), step {step_s} s from {step_from}{}",
            layout.acceleration_name,
            layout.unit.name(),
            layout.unit_from,
            match sep {
                Decimal::Comma => ", decimal commas",
                Decimal::Point => "",
            }
        ),
        acceleration_m_s2: acceleration,
    })
}

/// An error at line `line` (1-based) of `file`.
pub(super) fn line_error(file: &str, line: usize, message: String) -> MotionError {
    MotionError::Line {
        file: file.to_string(),
        line,
        message,
    }
}

/// A column file as read: its header line of names, if any, and its rows of numbers,
/// each with its line number (1-based).
struct ColumnRows {
    header: Option<(usize, Vec<String>)>,
    rows: Vec<(usize, Vec<f64>)>,
}

impl ColumnRows {
    /// Read `lines` with the decimal separator `sep`, comments skipped: a line that is
    /// not numbers before any row is the header; after that, the first cell that is not
    /// a number is an error at its line.
    fn read(lines: &[&str], sep: Decimal, file: &str) -> Result<Self, MotionError> {
        let mut rows: Vec<(usize, Vec<f64>)> = Vec::new();
        let mut header: Option<(usize, Vec<String>)> = None;
        for (i, line) in lines.iter().enumerate() {
            if is_comment(line) {
                continue;
            }
            match numbers_in(line, sep) {
                Some(v) => rows.push((i + 1, v)),
                None if header.is_none() && rows.is_empty() => {
                    header = Some((
                        i + 1,
                        cells(line, sep)
                            .map(|c| c.trim_matches('"').to_string())
                            .collect(),
                    ))
                }
                None => {
                    let bad = cells(line, sep)
                        .find(|c| number(c, sep).is_none())
                        .unwrap_or("");
                    return Err(line_error(file, i + 1, format!("`{bad}` is not a number")));
                }
            }
        }
        Ok(ColumnRows { header, rows })
    }

    /// The number of columns: the header's, else the first row's; every row must have
    /// as many values.
    fn width(&self, file: &str) -> Result<usize, MotionError> {
        let width = match (&self.header, self.rows.first()) {
            (Some((_, names)), _) => names.len(),
            (None, Some((_, r))) => r.len(),
            (None, None) => return Err(line_error(file, 1, "no rows of numbers".into())),
        };
        if let Some((line, r)) = self.rows.iter().find(|(_, r)| r.len() != width) {
            return Err(line_error(
                file,
                *line,
                format!("{} values where the file's first row has {width}", r.len()),
            ));
        }
        Ok(width)
    }

    /// The acceleration column in m/s^2; every value of it must be finite.
    fn acceleration(&self, layout: &ColumnLayout, file: &str) -> Result<Vec<f64>, MotionError> {
        let acceleration: Vec<f64> = self
            .rows
            .iter()
            .map(|(_, r)| r[layout.acceleration] * layout.unit.to_m_s2())
            .collect();
        if let Some((line, _)) = self
            .rows
            .iter()
            .find(|(_, r)| !r[layout.acceleration].is_finite())
        {
            return Err(line_error(
                file,
                *line,
                "the acceleration is not finite".into(),
            ));
        }
        Ok(acceleration)
    }

    /// The time step and where it comes from: the uniform step of the time column `time`
    /// (hinting at decimal commas where `lines` may be one column of them), else `--dt`.
    fn step(
        &self,
        time: Option<usize>,
        lines: &[&str],
        sep: Decimal,
        file: &str,
        options: &ReadOptions,
    ) -> Result<(f64, &'static str), MotionError> {
        match time {
            Some(t) => {
                let times: Vec<(usize, f64)> = self.rows.iter().map(|(l, r)| (*l, r[t])).collect();
                let step = uniform_step(&times, file, options.step_s);
                Ok((
                    step.map_err(|e| with_comma_hint(e, lines, sep))?,
                    "its time column",
                ))
            }
            None => match options.step_s {
                Some(dt) => Ok((dt, "--dt")),
                None => Err(MotionError::Read {
                    file: file.to_string(),
                    message: "no time column: give the time step with --dt (e.g. --dt 0.01)".into(),
                }),
            },
        }
    }
}

/// `e` with a hint when the file may be one column of decimal commas (`0,5` on every
/// line), which reads as a time and an acceleration column of integers.
fn with_comma_hint(e: MotionError, lines: &[&str], sep: Decimal) -> MotionError {
    let one_comma_column = sep == Decimal::Point
        && lines
            .iter()
            .filter(|l| !is_comment(l))
            .all(|l| numbers_in(l, Decimal::Comma).is_some_and(|v| v.len() == 1));
    match (one_comma_column, e) {
        (true, MotionError::Line { file, line, message }) => MotionError::Line {
            file,
            line,
            message: format!(
                "{message} (if the file is one column written with decimal commas, give --decimal-comma)"
            ),
        },
        (_, e) => e,
    }
}

/// Which columns hold time and acceleration, and the acceleration's unit.
struct ColumnLayout {
    time: Option<usize>,
    acceleration: usize,
    acceleration_name: String,
    unit: AccelerationUnit,
    unit_from: &'static str,
}

impl ColumnLayout {
    /// Which columns hold the time and the acceleration, and the acceleration's unit;
    /// errors name `file`.
    fn choose(
        header: Option<&(usize, Vec<String>)>,
        width: usize,
        file: &str,
        options: &ReadOptions,
    ) -> Result<Self, MotionError> {
        let err = |message: String| MotionError::Read {
            file: file.to_string(),
            message,
        };
        let names: Vec<String> = match header {
            Some((_, n)) => n.clone(),
            None => (1..=width).map(|k| format!("column {k}")).collect(),
        };
        let lower: Vec<String> = names.iter().map(|n| n.to_ascii_lowercase()).collect();
        let time = lower
            .iter()
            .position(|n| matches!(n.as_str(), "time_s" | "time" | "t" | "t_s" | "time [s]"))
            .or((header.is_none() && width == 2).then_some(0));
        let acceleration =
            acceleration_column(header.is_some(), width, &names, &lower, options, &err)?;
        let (unit, unit_from) =
            acceleration_unit(&names[acceleration], &lower[acceleration], options, &err)?;
        Ok(ColumnLayout {
            time,
            acceleration,
            acceleration_name: names[acceleration].clone(),
            unit,
            unit_from,
        })
    }
}

/// The acceleration's column among `width`: `--column` by number or name, else the only
/// data column of a headerless file, else the first of the usual names.
fn acceleration_column(
    has_header: bool,
    width: usize,
    names: &[String],
    lower: &[String],
    options: &ReadOptions,
    err: &dyn Fn(String) -> MotionError,
) -> Result<usize, MotionError> {
    Ok(match &options.column {
        Some(c) => match c.parse::<usize>() {
            Ok(k) if (1..=width).contains(&k) => k - 1,
            Ok(k) => return Err(err(format!("--column {k}: the file has {width} columns"))),
            Err(_) => lower
                .iter()
                .position(|n| *n == c.to_ascii_lowercase())
                .ok_or_else(|| {
                    err(format!(
                        "--column `{c}`: no such column (columns: {})",
                        names.join(", ")
                    ))
                })?,
        },
        None => match (has_header, width) {
            (false, 1) => 0,
            (false, 2) => 1,
            _ => [
                "acceleration_m_s2",
                "ref_acceleration_m_s2",
                "acceleration_g",
                "acceleration",
            ]
            .iter()
            .find_map(|want| lower.iter().position(|n| n == want))
            .ok_or_else(|| {
                err(format!(
                    "which column is the acceleration? give --column NAME or NUMBER (columns: {})",
                    names.join(", ")
                ))
            })?,
        },
    })
}

/// The acceleration's unit and where it came from: the column's name (`lower` is it in
/// lower case) or `--units`; both given, they must agree.
fn acceleration_unit(
    name: &str,
    lower: &str,
    options: &ReadOptions,
    err: &dyn Fn(String) -> MotionError,
) -> Result<(AccelerationUnit, &'static str), MotionError> {
    match (unit_from_name(lower), options.unit) {
        (Some(n), Some(u)) if n != u => Err(err(format!(
            "--units {} contradicts the column name `{}` ({})",
            u.name(),
            name,
            n.name()
        ))),
        (Some(n), _) => Ok((n, "from the column name")),
        (None, Some(u)) => Ok((u, "from --units")),
        (None, None) => Err(err(format!(
            "the unit of `{name}` is not known: give --units g, m/s2 or cm/s2"
        ))),
    }
}

/// The unit a column's name declares (`_m_s2`, `_g`, `_cm_s2`), if any.
fn unit_from_name(name: &str) -> Option<AccelerationUnit> {
    if name.ends_with("_cm_s2") || name.ends_with("[cm/s2]") || name.ends_with("[gal]") {
        Some(AccelerationUnit::CentimetrePerSecondSquared)
    } else if name.ends_with("_m_s2") || name.ends_with("[m/s2]") || name.ends_with("[m/s^2]") {
        Some(AccelerationUnit::MetrePerSecondSquared)
    } else if name.ends_with("_g") || name.ends_with("[g]") {
        Some(AccelerationUnit::StandardGravity)
    } else {
        None
    }
}

/// The uniform step of a time column, allowing the rounding of printed times
/// ([`TIME_ROUNDING_TOLERANCE`]); `given` (from `--dt`) must agree with it.
pub(super) fn uniform_step(
    times: &[(usize, f64)],
    file: &str,
    given: Option<f64>,
) -> Result<f64, MotionError> {
    let err_at = |line: usize, message: String| line_error(file, line, message);
    let (Some(&(_, t0)), Some(&(last_line, t1))) = (times.first(), times.last()) else {
        return Err(MotionError::Read {
            file: file.to_string(),
            message: "no samples".into(),
        });
    };
    let n = times.len();
    let step = least_squares_step(times);
    if !(step.is_finite() && step > 0.0 && t1 > t0) {
        return Err(err_at(last_line, "time does not increase".into()));
    }
    let t0 = times
        .iter()
        .enumerate()
        .map(|(k, &(_, t))| t - k as f64 * step)
        .sum::<f64>()
        / n as f64;
    for (k, &(line, t)) in times.iter().enumerate() {
        let expected = t0 + k as f64 * step;
        // written so that a NaN time fails too
        if (t - expected)
            .abs()
            .partial_cmp(&(TIME_ROUNDING_TOLERANCE * step))
            != Some(std::cmp::Ordering::Less)
        {
            return Err(err_at(
                line,
                format!(
                    "time {t} s is {:.3} steps off the uniform grid of step {step} s \
                     (more than rounding): resample the record to a uniform step first",
                    (t - expected) / step
                ),
            ));
        }
    }
    if let Some(dt) = given {
        if ((dt - step) / step).abs() > TIME_ROUNDING_TOLERANCE / (n - 1).max(1) as f64 + 1e-9 {
            return Err(MotionError::Read {
                file: file.to_string(),
                message: format!("--dt {dt} s contradicts the time column's step {step} s"),
            });
        }
    }
    Ok(step)
}

/// The slope of time against sample number: the step, with the rounding of printed times
/// averaged out (an end-to-end difference keeps the rounding of the last time).
fn least_squares_step(times: &[(usize, f64)]) -> f64 {
    let n = times.len() as f64;
    let k_mean = (n - 1.0) / 2.0;
    let t_mean = times.iter().map(|(_, t)| t).sum::<f64>() / n;
    let (mut num, mut den) = (0.0, 0.0);
    for (k, &(_, t)) in times.iter().enumerate() {
        num += (k as f64 - k_mean) * (t - t_mean);
        den += (k as f64 - k_mean).powi(2);
    }
    num / den
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(s: &str) -> Vec<&str> {
        s.lines().collect()
    }

    #[test]
    fn two_columns_give_time_and_acceleration() {
        let text = "# a lab export\n0.000 0.0\n0.010 0.5\n0.020 -0.25\n0.030 0.0\n";
        let opts = ReadOptions {
            unit: Some(AccelerationUnit::StandardGravity),
            ..Default::default()
        };
        let m = read_columns(&lines(text), "f", &opts).unwrap();
        assert!((m.step_s - 0.01).abs() < 1e-12);
        assert_eq!(m.acceleration_m_s2[1], 0.5 * STANDARD_GRAVITY_M_S2);
    }

    #[test]
    fn named_columns_carry_their_unit_and_a_contradiction_is_refused() {
        let text = "time_s,acceleration_m_s2,force_n\n0,1,5\n0.5,2,5\n1.0,3,5\n";
        let m = read_columns(&lines(text), "f", &ReadOptions::default()).unwrap();
        assert_eq!(m.acceleration_m_s2, vec![1.0, 2.0, 3.0]);
        assert_eq!(m.step_s, 0.5);
        let opts = ReadOptions {
            unit: Some(AccelerationUnit::StandardGravity),
            ..Default::default()
        };
        let e = read_columns(&lines(text), "f", &opts)
            .unwrap_err()
            .to_string();
        assert!(e.contains("contradicts"), "{e}");
    }

    #[test]
    fn rounded_times_pass_and_a_gap_is_refused_with_its_line() {
        // 1/1024 s printed to 4 decimals
        let mut text = String::new();
        for k in 0..50 {
            text.push_str(&format!("{:.4} {}\n", k as f64 / 1024.0, k));
        }
        let opts = ReadOptions {
            unit: Some(AccelerationUnit::MetrePerSecondSquared),
            ..Default::default()
        };
        let m = read_columns(&lines(&text), "f", &opts).unwrap();
        assert!((m.step_s - 1.0 / 1024.0).abs() < 1e-7, "{}", m.step_s);
        let gap = text.replace("0.0107 ", "0.0120 ");
        let e = read_columns(&lines(&gap), "f", &opts)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("f:12:"), "{e}");
    }

    #[test]
    fn one_column_needs_a_step_and_a_unit() {
        let text = "0.1\n0.2\n0.3\n";
        let e = read_columns(&lines(text), "f", &ReadOptions::default()).unwrap_err();
        assert!(e.to_string().contains("--units"), "{e}");
        let opts = ReadOptions {
            unit: Some(AccelerationUnit::StandardGravity),
            ..Default::default()
        };
        let e = read_columns(&lines(text), "f", &opts).unwrap_err();
        assert!(e.to_string().contains("--dt"), "{e}");
    }

    #[test]
    fn decimal_commas_are_read_where_a_delimiter_makes_them_unambiguous() {
        let opts = ReadOptions {
            unit: Some(AccelerationUnit::MetrePerSecondSquared),
            ..Default::default()
        };
        let want = [0.0, 0.5, -0.25, 1.5e-3];
        for text in [
            "0,000;0,0\n0,010;0,5\n0,020;-0,25\n0,030;1,5e-3\n",
            "time_s\tacceleration_m_s2\n0,00\t0\n0,01\t0,5\n0,02\t-0,25\n0,03\t1,5e-3\n",
        ] {
            let m = read_columns(&lines(text), "f", &opts).unwrap();
            assert!((m.step_s - 0.01).abs() < 1e-12, "{text}: {}", m.step_s);
            assert_eq!(m.acceleration_m_s2, want, "{text}");
            assert!(m.source.contains("decimal commas"), "{}", m.source);
        }
        // a comma and a space delimit integers: not `0.` and `1`
        let m = read_columns(&lines("0, 1\n1, 2\n2, 3\n"), "f", &opts).unwrap();
        assert_eq!((m.step_s, m.acceleration_m_s2[2]), (1.0, 3.0));
        // one column of `0,5` is two integer columns unless told
        let one = "0,5\n0,25\n-1,0\n";
        assert_eq!(decimal_of(&lines(one), false), Decimal::Point);
        let told = ReadOptions {
            step_s: Some(0.01),
            decimal_comma: true,
            ..opts.clone()
        };
        let e = read_columns(&lines(one), "f", &opts).unwrap_err();
        assert!(e.to_string().contains("give --decimal-comma"), "{e}");
        let m = read_columns(&lines(one), "f", &told).unwrap();
        assert_eq!(m.acceleration_m_s2, [0.5, 0.25, -1.0]);
        // a thousands point is not a number
        let e = read_columns(&lines("0;1\n1;1.000,5\n"), "f", &told).unwrap_err();
        assert!(e.to_string().contains("`1.000,5` is not a number"), "{e}");
    }

    #[test]
    fn a_word_among_the_numbers_is_named_with_its_line() {
        let text = "0 1\n0.1 2\n0.2 x\n";
        let opts = ReadOptions {
            unit: Some(AccelerationUnit::StandardGravity),
            ..Default::default()
        };
        let e = read_columns(&lines(text), "f", &opts)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "f:3: `x` is not a number");
    }
}
