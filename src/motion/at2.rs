//! PEER NGA strong-motion files (`.AT2`): four header lines (database, event and
//! component, units, `NPTS= n, DT= dt SEC`, or the older `n dt NPTS, DT`), then the
//! samples, several to a line.

use super::read::{line_error, numbers, AccelerationUnit, GroundMotion, ReadOptions};
use super::MotionError;

/// Lines before the samples in an AT2 file.
const HEADER_LINES: usize = 4;

/// Read an AT2 file's lines.
pub fn read_at2(
    lines: &[&str],
    file: &str,
    options: &ReadOptions,
) -> Result<GroundMotion, MotionError> {
    let header = At2Header::read(lines, file, options)?;
    let samples = header.samples(lines, file)?;
    let At2Header { unit, npts, dt } = header;
    Ok(GroundMotion {
        step_s: dt,
        acceleration_m_s2: samples,
        source: format!(
            "{file}: PEER NGA AT2 `{}`, {npts} samples in {}, DT = {dt} s from its header",
            lines[1].trim(),
            unit.name()
        ),
    })
}

/// What an AT2 file's header says: the acceleration's unit, the number of samples and
/// the time step, s.
struct At2Header {
    unit: AccelerationUnit,
    npts: usize,
    dt: f64,
}

impl At2Header {
    /// Read the header (the unit on its third line, NPTS and DT on its fourth), each
    /// checked against `--units` and `--dt` where given.
    fn read(lines: &[&str], file: &str, options: &ReadOptions) -> Result<Self, MotionError> {
        if lines.len() <= HEADER_LINES {
            return Err(line_error(
                file,
                lines.len().max(1),
                "an AT2 file has four header lines and then the samples".into(),
            ));
        }
        let unit = checked_unit(lines[2], file, options)?;
        let (npts, dt) = checked_npts_dt(lines[3], file, options)?;
        Ok(At2Header { unit, npts, dt })
    }

    /// The samples after the header in m/s^2: every value a finite number, exactly
    /// NPTS of them (more is an error at the line that passes NPTS).
    fn samples(&self, lines: &[&str], file: &str) -> Result<Vec<f64>, MotionError> {
        let (unit, npts) = (self.unit, self.npts);
        let mut samples = Vec::with_capacity(npts.min(1 << 24));
        for (i, line) in lines.iter().enumerate().skip(HEADER_LINES) {
            let values = numbers(line)
                .ok_or_else(|| line_error(file, i + 1, "a value is not a number".into()))?;
            if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                return Err(line_error(
                    file,
                    i + 1,
                    format!("{v} is not a finite acceleration"),
                ));
            }
            samples.extend(values.iter().map(|v| v * unit.to_m_s2()));
            if samples.len() > npts {
                return Err(line_error(
                    file,
                    i + 1,
                    format!("more samples than the header's NPTS = {npts}"),
                ));
            }
        }
        if samples.len() < npts {
            return Err(line_error(
                file,
                lines.len(),
                format!(
                    "{} samples where the header says NPTS = {npts}",
                    samples.len()
                ),
            ));
        }
        Ok(samples)
    }
}

/// The unit on the header's third line `line`, which `--units` must not contradict.
fn checked_unit(
    line: &str,
    file: &str,
    options: &ReadOptions,
) -> Result<AccelerationUnit, MotionError> {
    let unit = header_unit(line).ok_or_else(|| {
        line_error(
            file,
            3,
            format!(
                "no unit of acceleration (G, CM/S/S or M/S/S) in `{}`",
                line.trim()
            ),
        )
    })?;
    if let Some(u) = options.unit.filter(|u| *u != unit) {
        return Err(line_error(
            file,
            3,
            format!(
                "--units {} contradicts the header ({})",
                u.name(),
                unit.name()
            ),
        ));
    }
    Ok(unit)
}

/// NPTS and DT on the header's fourth line `line`; `--dt` must agree with DT.
fn checked_npts_dt(
    line: &str,
    file: &str,
    options: &ReadOptions,
) -> Result<(usize, f64), MotionError> {
    let (npts, dt) = npts_dt(line).ok_or_else(|| {
        line_error(
            file,
            4,
            format!("expected `NPTS= n, DT= step SEC`, found `{}`", line.trim()),
        )
    })?;
    if let Some(given) = options.step_s {
        if (given - dt).abs() > 1e-9 * dt {
            return Err(line_error(
                file,
                4,
                format!("--dt {given} s contradicts the header's DT = {dt} s"),
            ));
        }
    }
    Ok((npts, dt))
}

/// The unit named on the header's third line.
fn header_unit(line: &str) -> Option<AccelerationUnit> {
    let l = line.to_ascii_uppercase();
    if l.contains("CM/S") || l.contains("CM/SEC") || l.contains("GAL") {
        Some(AccelerationUnit::CentimetrePerSecondSquared)
    } else if l.contains("M/S") || l.contains("M/SEC") {
        Some(AccelerationUnit::MetrePerSecondSquared)
    } else if l.contains("UNITS OF G") || l.split_whitespace().any(|w| w == "G" || w == "(G)") {
        Some(AccelerationUnit::StandardGravity)
    } else {
        None
    }
}

/// NPTS and DT from `NPTS=  4000, DT=   .0100 SEC` or `4000   .0100   NPTS, DT`.
fn npts_dt(line: &str) -> Option<(usize, f64)> {
    let upper = line.to_ascii_uppercase();
    let after = |key: &str| -> Option<f64> {
        let rest = &upper[upper.find(key)? + key.len()..];
        let rest = rest.trim_start_matches([' ', '=', ':']);
        let end = rest
            .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'E')))
            .unwrap_or(rest.len());
        rest[..end].parse().ok()
    };
    let (npts, dt) = match (after("NPTS"), after("DT")) {
        (Some(n), Some(d)) => (n, d),
        _ => {
            let v: Vec<f64> = upper
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter_map(|w| w.parse().ok())
                .collect();
            (*v.first()?, *v.get(1)?)
        }
    };
    let whole = npts >= 1.0 && npts.fract() == 0.0 && npts < 1e8;
    (whole && dt.is_finite() && dt > 0.0).then_some((npts as usize, dt))
}

#[cfg(test)]
mod tests {
    use super::*;

    const AT2: &str = "PEER NGA STRONG MOTION DATABASE RECORD\n\
        Imperial Valley-02, 5/19/1940, El Centro Array #9, 180\n\
        ACCELERATION TIME SERIES IN UNITS OF G\n\
        NPTS=    7, DT=   .0100 SEC\n\
        \x20 .1E-01  -.2000E-01  .30E-01  .0\n\
        \x20 -.5E-01  .6E-01  -.07\n";

    #[test]
    fn reads_the_header_and_the_samples() {
        let lines: Vec<&str> = AT2.lines().collect();
        let m = read_at2(&lines, "x.AT2", &ReadOptions::default()).unwrap();
        assert_eq!(m.step_s, 0.01);
        assert_eq!(m.acceleration_m_s2.len(), 7);
        assert!((m.acceleration_m_s2[6] + 0.07 * 9.80665).abs() < 1e-12);
        assert!(m.source.contains("El Centro"), "{}", m.source);
    }

    #[test]
    fn the_old_header_form_and_count_mismatches() {
        assert_eq!(npts_dt("  4000   .0050   NPTS, DT"), Some((4000, 0.005)));
        assert_eq!(npts_dt("NPTS=  4000, DT=   .0050 SEC"), Some((4000, 0.005)));
        assert_eq!(npts_dt("NPTS= 12.5, DT= .01"), None);
        let short = AT2.replace("NPTS=    7", "NPTS=    9");
        let lines: Vec<&str> = short.lines().collect();
        let e = read_at2(&lines, "x.AT2", &ReadOptions::default()).unwrap_err();
        assert!(
            e.to_string()
                .contains("7 samples where the header says NPTS = 9"),
            "{e}"
        );
        let long = AT2.replace("NPTS=    7", "NPTS=    5");
        let lines: Vec<&str> = long.lines().collect();
        let e = read_at2(&lines, "x.AT2", &ReadOptions::default()).unwrap_err();
        assert!(e.to_string().starts_with("x.AT2:6:"), "{e}");
    }
}
