//! campaign.toml's values: line numbers from byte offsets for errors, the type and number
//! of a TOML value, the plausible physical ranges of campaign.toml's values, and the
//! checked lookups every table reader uses.

use super::*;

pub(super) type RawTable = BTreeMap<Spanned<String>, Spanned<toml::Value>>;

/// Line numbers from byte offsets.
pub(super) struct Lines<'a> {
    pub(super) text: &'a str,
    pub(super) file: &'a str,
}

impl Lines<'_> {
    pub(super) fn line(&self, offset: usize) -> usize {
        let end = offset.min(self.text.len());
        self.text.as_bytes()[..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1
    }

    pub(super) fn err(
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

pub(super) fn type_name(v: &toml::Value) -> &'static str {
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

pub(super) fn as_number(v: &toml::Value) -> Option<f64> {
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
pub(super) struct Bound {
    pub(super) min: f64,
    pub(super) max: f64,
    pub(super) unit: &'static str,
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

pub(super) const PISTON_AREA_M2: Bound = Bound::of(params::PISTON_AREA_M2, "m^2");
pub(super) const OIL_VOLUME_M3: Bound = Bound::of(params::OIL_VOLUME_M3, "m^3");
pub(super) const SUPPLY_PRESSURE_PA: Bound = Bound::of(params::SUPPLY_PRESSURE_PA, "Pa");
pub(super) const FLOW_GAIN_M3_S: Bound = Bound::of(params::FLOW_GAIN_M3_S, "m^3/s");
/// Sample rate: 1 Hz to 1 MHz (controllers sample at 0.5 to 10 kHz, fast DAQs 100 kHz).
pub(super) const SAMPLE_RATE_HZ: Bound = Bound {
    min: 1.0,
    max: 1e6,
    unit: "Hz",
};
/// A test frequency (sine, triangle, band edge): from 1e-4 Hz (a period of 2.8 hours,
/// longer than any test) up to the Nyquist frequency (checked separately).
pub(super) const TEST_FREQUENCY_HZ: Bound = Bound {
    min: 1e-4,
    max: 5e5,
    unit: "Hz",
};
/// A displacement level (amplitude, RMS): 1 nm (below any LVDT's resolution) to 10 m
/// (ten times the longest strokes, +-1 m).
pub(super) const DISPLACEMENT_M: Bound = Bound {
    min: 1e-9,
    max: 10.0,
    unit: "m",
};
/// An acceleration level (RMS): 1 micro-g to 1000 g (a hundred times the strongest tables).
pub(super) const ACCELERATION_M_S2: Bound = Bound {
    min: 1e-5,
    max: 1e4,
    unit: "m/s^2",
};

/// The rule `x` breaks against bound `b`, if any.
pub(super) fn broken(x: f64, b: Bound) -> Option<String> {
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

/// A number from a spanned value, checked.
pub(super) fn number(
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

pub(super) fn lookup<'t>(t: &'t RawTable, key: &str) -> Option<&'t Spanned<toml::Value>> {
    t.iter().find(|(k, _)| k.get_ref() == key).map(|(_, v)| v)
}

pub(super) fn required_string<'t>(
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
