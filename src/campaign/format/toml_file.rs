//! campaign.toml: parsing with the line, test and key of every error, and the
//! plausible physical ranges of its values.

use super::*;

pub(super) type RawTable = BTreeMap<Spanned<String>, Spanned<toml::Value>>;

#[derive(serde::Deserialize)]
pub(super) struct RawDoc {
    name: Option<Spanned<toml::Value>>,
    sample_rate_hz: Option<Spanned<toml::Value>>,
    geometry: Option<Spanned<RawTable>>,
    controller: Option<Spanned<RawTable>>,
    test: Option<Spanned<Vec<Spanned<RawTable>>>>,
    read: Option<Spanned<toml::Value>>,
    columns: Option<Spanned<toml::Value>>,
}

/// Line numbers from byte offsets.
pub(super) struct Lines<'a> {
    text: &'a str,
    file: &'a str,
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
    min: f64,
    max: f64,
    unit: &'static str,
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
/// Largest magnitude of each TVC gain (spec section 2, u normalised to [-1, 1]): the gain
/// that opens the valve fully for an error of 1 nm, 1 nm/s, 1 nm/s^2 or 1 micro-newton,
/// a thousand times finer than any table's sensors resolve. The sign is not restricted
/// here: an unstable loop is reported by the stability check, not as a format error.
pub(super) const GAIN_LIMITS: [(&str, f64, &str); 6] = [
    ("kp", 1e9, "1/m"),
    ("kv", 1e9, "s/m"),
    ("ka", 1e9, "s^2/m"),
    ("fv", 1e9, "s/m"),
    ("fa", 1e9, "s^2/m"),
    ("kdp", 1e6, "1/N"),
];

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

/// The magnitude bound of gain `key`.
pub(super) fn gain_check(key: &str) -> Bound {
    let (_, max, unit) = GAIN_LIMITS
        .iter()
        .find(|(k, _, _)| *k == key)
        .copied()
        .unwrap_or(("", f64::MAX, ""));
    Bound {
        min: -max,
        max,
        unit,
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

pub(super) const GAINS: [&str; 6] = ["kp", "kv", "ka", "fv", "fa", "kdp"];

/// `[controller]`: every gain required, finite; unknown gains are errors.
/// `[controller]`: each gain given is checked; one not given is unknown
/// (campaign-format.md).
pub(super) fn read_controller(
    lines: &Lines,
    c: &Spanned<RawTable>,
) -> Result<ControllerOverride, CampaignError> {
    let off = c.span().start;
    let t = c.get_ref();
    for (k, _) in t.iter() {
        if !GAINS.contains(&k.get_ref().as_str()) {
            return Err(lines.err(
                Some(k.span().start),
                None,
                Some(&format!("controller.{}", k.get_ref())),
                format!(
                    "unknown controller gain; the gains are {}",
                    GAINS.join(", ")
                ),
            ));
        }
    }
    let _ = off;
    let g = |key: &str| -> Result<Option<f64>, CampaignError> {
        lookup(t, key)
            .map(|v| {
                number(lines, v, None, key, gain_check(key))
                    .map_err(|e| rename_key(e, &format!("controller.{key}")))
            })
            .transpose()
    };
    Ok(ControllerOverride {
        kp: g("kp")?,
        kv: g("kv")?,
        ka: g("ka")?,
        fv: g("fv")?,
        fa: g("fa")?,
        kdp: g("kdp")?,
    })
}

pub(super) fn rename_key(e: CampaignError, new_key: &str) -> CampaignError {
    match e {
        CampaignError::Toml {
            file,
            line,
            test,
            message,
            ..
        } => CampaignError::Toml {
            file,
            line,
            test,
            key: Some(new_key.to_string()),
            message,
        },
        other => other,
    }
}

/// A test's `controller = { ... }` override.
pub(super) fn read_override(
    lines: &Lines,
    v: &Spanned<toml::Value>,
    test: &str,
) -> Result<ControllerOverride, CampaignError> {
    let off = Some(v.span().start);
    let toml::Value::Table(t) = v.get_ref() else {
        return Err(lines.err(
            off,
            Some(test),
            Some("controller"),
            format!(
                "expected a table of gains like {{ fv = 0.0 }}, found {}",
                type_name(v.get_ref())
            ),
        ));
    };
    let mut o = ControllerOverride::default();
    for (k, val) in t {
        let key = format!("controller.{k}");
        let x = as_number(val).ok_or_else(|| {
            lines.err(
                off,
                Some(test),
                Some(&key),
                format!("expected a number, found {}", type_name(val)),
            )
        })?;
        if let Some(rule) = broken(x, gain_check(k)) {
            return Err(lines.err(off, Some(test), Some(&key), rule));
        }
        let slot = match k.as_str() {
            "kp" => &mut o.kp,
            "kv" => &mut o.kv,
            "ka" => &mut o.ka,
            "fv" => &mut o.fv,
            "fa" => &mut o.fa,
            "kdp" => &mut o.kdp,
            _ => {
                return Err(lines.err(
                    off,
                    Some(test),
                    Some(&key),
                    format!(
                        "unknown controller gain; the gains are {}",
                        GAINS.join(", ")
                    ),
                ))
            }
        };
        *slot = Some(x);
    }
    Ok(o)
}

/// A test's `file`, lexically (before any file system access): inside the campaign
/// folder, not the folder itself, not campaign.toml.
pub(super) fn check_test_file(
    lines: &Lines,
    file: &str,
    file_off: usize,
    test: Option<&str>,
) -> Result<(), CampaignError> {
    let why = match normalise_relative(file) {
        None => "is outside the campaign folder: a test file must be a path inside it, relative to campaign.toml (not opened)",
        Some(p) if p.as_os_str().is_empty() => "names the campaign folder itself, not a file",
        Some(p) if p == Path::new("campaign.toml") => "is campaign.toml itself, not a record",
        Some(_) => return Ok(()),
    };
    Err(lines.err(
        Some(file_off),
        test,
        Some("file"),
        format!("`{file}` {why}"),
    ))
}

/// One `[[test]]` entry; `campaign_rate_hz` is the campaign's `sample_rate_hz`, the
/// test's own (campaign-format.md, "campaign.toml additions") replaces it for the test's
/// Nyquist checks.
pub(super) fn read_test(
    lines: &Lines,
    raw: &Spanned<RawTable>,
    index: usize,
    campaign_rate_hz: f64,
) -> Result<(TestSpec, usize), CampaignError> {
    let off = raw.span().start;
    let t = raw.get_ref();
    let (name, _) = required_string(lines, t, off, None, "name", "every [[test]] needs a name")
        .map_err(|e| match e {
            CampaignError::Toml {
                file,
                line,
                key,
                message,
                ..
            } => CampaignError::Toml {
                file,
                line,
                test: Some(format!("#{} (unnamed)", index + 1)),
                key,
                message,
            },
            other => other,
        })?;
    let name = name.to_string();
    let tn = Some(name.as_str());
    if name.trim().is_empty() {
        return Err(lines.err(Some(off), tn, Some("name"), "test name is empty"));
    }
    let (file, file_off) = required_string(lines, t, off, tn, "file", "the CSV of the test")?;
    if file.trim().is_empty() {
        return Err(lines.err(Some(file_off), tn, Some("file"), "file name is empty"));
    }
    check_test_file(lines, file, file_off, tn)?;
    let (kind_s, kind_off) = required_string(
        lines,
        t,
        off,
        tn,
        "kind",
        "random | sine | triangle | record",
    )?;
    let kind = match kind_s {
        "random" => TestKind::Random,
        "sine" => TestKind::Sine,
        "triangle" => TestKind::Triangle,
        "record" => TestKind::Record,
        other => {
            return Err(lines.err(
                Some(kind_off),
                tn,
                Some("kind"),
                format!("unknown kind `{other}`; expected random | sine | triangle | record"),
            ))
        }
    };
    let (control_s, control_off) =
        required_string(lines, t, off, tn, "control", "displacement | acceleration")?;
    let control = match control_s {
        "displacement" => Control::Displacement,
        "acceleration" => Control::Acceleration,
        other => {
            return Err(lines.err(
                Some(control_off),
                tn,
                Some("control"),
                format!("unknown control `{other}`; expected displacement | acceleration"),
            ))
        }
    };
    let mut spec = TestSpec::new(name.clone(), file, kind, control);
    let optional = |key: &str, check: Bound| -> Result<Option<f64>, CampaignError> {
        lookup(t, key)
            .map(|v| number(lines, v, tn, key, check))
            .transpose()
    };
    let level = match control {
        Control::Displacement => DISPLACEMENT_M,
        Control::Acceleration => ACCELERATION_M_S2,
    };
    // the test's own rate, checked like the campaign's; its Nyquist bounds the test
    spec.sample_rate_hz = optional("sample_rate_hz", SAMPLE_RATE_HZ)?;
    let sample_rate_hz = spec.sample_rate_hz.unwrap_or(campaign_rate_hz);
    spec.rms = optional("rms", level)?;
    spec.frequency_hz = optional("frequency_hz", TEST_FREQUENCY_HZ)?;
    spec.amplitude_m = optional("amplitude_m", DISPLACEMENT_M)?;
    if let Some(f) = spec.frequency_hz.filter(|&f| f > sample_rate_hz / 2.0) {
        let v = lookup(t, "frequency_hz").map(|v| v.span().start);
        return Err(lines.err(
            v,
            tn,
            Some("frequency_hz"),
            format!(
                "{f} Hz is above the Nyquist frequency {} Hz of sample_rate_hz",
                sample_rate_hz / 2.0
            ),
        ));
    }
    if let Some(v) = lookup(t, "band_hz") {
        let voff = Some(v.span().start);
        let bad = |m: String| lines.err(voff, tn, Some("band_hz"), m);
        let toml::Value::Array(a) = v.get_ref() else {
            return Err(bad(format!(
                "expected [low, high] in Hz, found {}",
                type_name(v.get_ref())
            )));
        };
        let nums: Vec<f64> = a.iter().filter_map(as_number).collect();
        if a.len() != 2 || nums.len() != 2 {
            return Err(bad("expected two numbers [low, high] in Hz".to_string()));
        }
        let (lo, hi) = (nums[0], nums[1]);
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
            return Err(bad(format!("[{lo}, {hi}]: need 0 <= low < high")));
        }
        if lo > 0.0 && lo < TEST_FREQUENCY_HZ.min {
            return Err(bad(format!(
                "[{lo}, {hi}]: a low edge above 0 must be at least {} Hz (0 for a band from DC)",
                TEST_FREQUENCY_HZ.min
            )));
        }
        if hi > sample_rate_hz / 2.0 {
            return Err(bad(format!(
                "[{lo}, {hi}]: the band goes above the Nyquist frequency {} Hz of sample_rate_hz",
                sample_rate_hz / 2.0
            )));
        }
        spec.band_hz = Some([lo, hi]);
    }
    match kind {
        TestKind::Random => {
            let why = "a random test needs its level (m RMS for displacement control, m/s^2 RMS for acceleration control)";
            if spec.rms.is_none() {
                return Err(lines.err(
                    Some(off),
                    tn,
                    Some("rms"),
                    format!("required key is missing ({why})"),
                ));
            }
            if spec.band_hz.is_none() {
                return Err(lines.err(
                    Some(off),
                    tn,
                    Some("band_hz"),
                    "required key is missing (a random test needs its band [low, high] in Hz)",
                ));
            }
        }
        TestKind::Sine | TestKind::Triangle => {
            let k = if kind == TestKind::Sine {
                "sine"
            } else {
                "triangle"
            };
            if spec.frequency_hz.is_none() {
                return Err(lines.err(
                    Some(off),
                    tn,
                    Some("frequency_hz"),
                    format!("required key is missing (a {k} test needs its frequency in Hz)"),
                ));
            }
            if spec.amplitude_m.is_none() {
                return Err(lines.err(
                    Some(off),
                    tn,
                    Some("amplitude_m"),
                    format!("required key is missing (a {k} test needs its displacement amplitude in m)"),
                ));
            }
        }
        // any reference: nothing more is needed
        TestKind::Record => {}
    }
    if let Some(v) = lookup(t, "controller") {
        spec.controller = read_override(lines, v, &name)?;
    }
    Ok((spec, file_off))
}

/// Parse campaign.toml text. `file` names it in errors; `default_name` is used when the
/// file has no `name`. Returns the info and, per test, the line of its `file` key.
pub fn parse_campaign_toml(
    text: &str,
    file: &str,
    default_name: &str,
) -> Result<(CampaignInfo, Vec<usize>), CampaignError> {
    parse_campaign_toml_planned(text, file, default_name).map(|(info, lines, _)| (info, lines))
}

/// [`parse_campaign_toml`] with each test's [`ReadPlan`]: how its file is read.
pub fn parse_campaign_toml_planned(
    text: &str,
    file: &str,
    default_name: &str,
) -> Result<(CampaignInfo, Vec<usize>, Vec<ReadPlan>), CampaignError> {
    // classic Mac line ends (a lone CR) read as line ends; offsets are unchanged
    let text = lone_cr_to_lf(text);
    let text: &str = &text;
    let lines = Lines { text, file };
    let doc: RawDoc = toml::from_str(text).map_err(|e| {
        let msg = e.message().trim().to_string();
        lines.err(
            e.span().map(|s| s.start),
            None,
            None,
            format!("not valid TOML: {msg}"),
        )
    })?;
    let name = match &doc.name {
        Some(v) => match v.get_ref() {
            toml::Value::String(s) => s.clone(),
            other => {
                return Err(lines.err(
                    Some(v.span().start),
                    None,
                    Some("name"),
                    format!("expected a string, found {}", type_name(other)),
                ))
            }
        },
        None => default_name.to_string(),
    };
    let sample_rate_hz = match &doc.sample_rate_hz {
        Some(v) => number(&lines, v, None, "sample_rate_hz", SAMPLE_RATE_HZ)?,
        None => {
            return Err(lines.err(
                None,
                None,
                Some("sample_rate_hz"),
                "required key is missing (the sampling rate of every record, Hz)",
            ))
        }
    };
    // every key of [geometry] and [controller] is optional: one not given is unknown
    let geometry = match &doc.geometry {
        Some(g) => {
            let get = |key: &str, bound: Bound| -> Result<Option<f64>, CampaignError> {
                lookup(g.get_ref(), key)
                    .map(|v| {
                        number(&lines, v, None, key, bound)
                            .map_err(|e| rename_key(e, &format!("geometry.{key}")))
                    })
                    .transpose()
            };
            Geometry {
                piston_area_m2: get("piston_area_m2", PISTON_AREA_M2)?,
                total_oil_volume_m3: get("total_oil_volume_m3", OIL_VOLUME_M3)?,
                supply_pressure_pa: get("supply_pressure_pa", SUPPLY_PRESSURE_PA)?,
                flow_gain_m3_s: get("flow_gain_m3_s", FLOW_GAIN_M3_S)?,
            }
        }
        None => Geometry::default(),
    };
    let controller = match &doc.controller {
        Some(c) => read_controller(&lines, c)?,
        None => ControllerOverride::default(),
    };
    let raw_tests = match &doc.test {
        Some(t) if !t.get_ref().is_empty() => t,
        Some(t) => {
            return Err(lines.err(
                Some(t.span().start),
                None,
                Some("test"),
                "the campaign has no tests",
            ))
        }
        None => {
            return Err(lines.err(
                None,
                None,
                Some("test"),
                "the campaign has no [[test]] entries",
            ))
        }
    };
    let campaign_read = match &doc.read {
        Some(v) => toml_layout::read_options(&lines, v.span().start, None, v.get_ref())?,
        None => ReadOverride::default(),
    };
    let campaign_columns = match &doc.columns {
        Some(v) => toml_layout::columns(&lines, v.span().start, None, v.get_ref())?,
        None => BTreeMap::new(),
    };
    let lab_form = doc.read.is_some()
        || doc.columns.is_some()
        || raw_tests.get_ref().iter().any(|t| {
            lookup(t.get_ref(), "read").is_some() || lookup(t.get_ref(), "columns").is_some()
        });
    let mut tests: Vec<TestSpec> = Vec::new();
    let mut plans: Vec<ReadPlan> = Vec::new();
    let mut file_lines = Vec::new();
    let mut header_lines: Vec<usize> = Vec::new();
    for (i, raw) in raw_tests.get_ref().iter().enumerate() {
        let (spec, file_off) = read_test(&lines, raw, i, sample_rate_hz)?;
        let here = lines.line(raw.span().start);
        let mut plan = test_plan(
            &lines,
            raw,
            &spec,
            sample_rate_hz,
            &campaign_read,
            &campaign_columns,
        )?;
        plan.lab_form = lab_form;
        if let Some(j) = tests.iter().position(|t| t.name == spec.name) {
            return Err(lines.err(
                Some(raw.span().start),
                Some(&spec.name),
                Some("name"),
                format!(
                    "duplicate test name: already used by the test at line {}",
                    header_lines[j]
                ),
            ));
        }
        // one file may hold several tests in a laboratory's form, each with its columns
        let same = |j: &usize| {
            normalise_relative(&tests[*j].file) == normalise_relative(&spec.file)
                && (!lab_form || plans[*j].columns == plan.columns)
        };
        if let Some(j) = (0..tests.len()).find(same) {
            return Err(lines.err(
                Some(file_off),
                Some(&spec.name),
                Some("file"),
                format!(
                    "`{}` is already the file of test `{}` (line {}){}",
                    spec.file,
                    tests[j].name,
                    file_lines[j],
                    if lab_form {
                        " with the same columns"
                    } else {
                        ""
                    }
                ),
            ));
        }
        plans.push(plan);
        header_lines.push(here);
        file_lines.push(lines.line(file_off));
        tests.push(spec);
    }
    Ok((
        CampaignInfo {
            name,
            sample_rate_hz,
            geometry,
            controller,
            tests,
        },
        file_lines,
        plans,
    ))
}

/// How test `spec`'s file is read: `[read]` and `[columns]` with the test's overrides.
fn test_plan(
    lines: &Lines,
    raw: &Spanned<RawTable>,
    spec: &TestSpec,
    sample_rate_hz: f64,
    campaign_read: &ReadOverride,
    campaign_columns: &BTreeMap<String, ColumnEntry>,
) -> Result<ReadPlan, CampaignError> {
    let t = raw.get_ref();
    let name = Some(spec.name.as_str());
    let test_read = match lookup(t, "read") {
        Some(v) => toml_layout::read_options(lines, v.span().start, name, v.get_ref())?,
        None => ReadOverride::default(),
    };
    let (test_columns, columns_off) = match lookup(t, "columns") {
        Some(v) => (
            toml_layout::columns(lines, v.span().start, name, v.get_ref())?,
            v.span().start,
        ),
        None => (BTreeMap::new(), raw.span().start),
    };
    // the test's own rate was checked with the test ([`read_test`])
    let own_rate_line = lookup(t, "sample_rate_hz").map(|v| lines.line(v.span().start));
    let columns = merge_columns(campaign_columns, &test_columns)
        .map_err(|m| lines.err(Some(columns_off), name, Some("columns"), m))?;
    Ok(ReadPlan {
        read: ReadOptions::default()
            .merged(campaign_read)
            .merged(&test_read),
        columns,
        lab_form: false,
        sample_rate_hz: spec.sample_rate_hz.unwrap_or(sample_rate_hz),
        own_rate_line,
        control: spec.control,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A campaign at 512 Hz with a random test `A` and a sine `B`; `a` and `b` are added
    /// to their entries.
    fn toml(a: &str, b: &str) -> String {
        format!(
            "sample_rate_hz = 512.0\n\n[[test]]\nname = \"A\"\nfile = \"A.csv\"\nkind = \"random\"\n\
             control = \"displacement\"\nrms = 0.001\nband_hz = [0.0, 100.0]\n{a}\n\n[[test]]\n\
             name = \"B\"\nfile = \"B.csv\"\nkind = \"sine\"\ncontrol = \"displacement\"\n\
             frequency_hz = 1.0\namplitude_m = 0.01\n{b}\n"
        )
    }

    fn parse(text: &str) -> Result<(CampaignInfo, Vec<ReadPlan>), CampaignError> {
        parse_campaign_toml_planned(text, "campaign.toml", "c").map(|(i, _, p)| (i, p))
    }

    #[test]
    fn a_test_keeps_its_own_rate_and_its_plan_reads_at_it() {
        let (info, plans) = parse(&toml("sample_rate_hz = 1000", "")).unwrap();
        let (a, b) = (&info.tests[0], &info.tests[1]);
        assert_eq!(a.sample_rate_hz, Some(1000.0));
        assert_eq!(b.sample_rate_hz, None);
        assert_eq!(info.sample_rate_for(a), 1000.0);
        assert_eq!(info.sample_rate_for(b), 512.0);
        assert_eq!(plans[0].sample_rate_hz, 1000.0);
        assert_eq!(plans[0].own_rate_line, Some(10));
        assert_eq!(
            (plans[1].sample_rate_hz, plans[1].own_rate_line),
            (512.0, None)
        );
    }

    #[test]
    fn a_bad_own_rate_names_line_test_and_key() {
        for (bad, why) in [
            ("0", "must be a finite number > 0"),
            ("-1000.0", "must be a finite number > 0"),
            ("nan", "must be finite"),
            ("inf", "must be finite"),
            ("1e9", "outside the plausible range"),
            ("\"1 kHz\"", "expected a number"),
        ] {
            let e = parse(&toml("", &format!("sample_rate_hz = {bad}")))
                .unwrap_err()
                .to_string();
            let want = "campaign.toml: line 19: test `B`: key `sample_rate_hz`: ";
            assert!(e.starts_with(want) && e.contains(why), "{bad}: {e}");
        }
    }

    #[test]
    fn nyquist_checks_use_the_tests_own_rate() {
        // 300 Hz is above 512 Hz's Nyquist but below 1 kHz's
        let fast = "sample_rate_hz = 1000.0\nband_hz = [0.0, 300.0]";
        let text = toml("", "").replace("band_hz = [0.0, 100.0]\n", "");
        assert!(parse(&text.replace("rms = 0.001\n", &format!("rms = 0.001\n{fast}\n"))).is_ok());
        let e = parse(&text.replace("rms = 0.001\n", "rms = 0.001\nband_hz = [0.0, 300.0]\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("Nyquist frequency 256 Hz"), "{e}");
        // and a slower test is bounded by its own, lower Nyquist
        let e = parse(&toml("", "sample_rate_hz = 1.5"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("test `B`") && e.contains("Nyquist frequency 0.75 Hz"),
            "{e}"
        );
    }
}
