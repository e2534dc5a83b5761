//! One `[[test]]` entry of campaign.toml: its name, file (lexically inside the folder),
//! kind, control, levels, frequencies, band, gains and rate, each checked.

use super::toml_gains::read_override;
use super::toml_values::*;
use super::*;

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
/// Nyquist checks; `time_rate_hz`, the rate of its time column once read, is the last
/// resort (no rate known: the checks wait for it).
pub(super) fn read_test(
    lines: &Lines,
    raw: &Spanned<RawTable>,
    index: usize,
    campaign_rate_hz: Option<f64>,
    time_rate_hz: Option<f64>,
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
    let (sample_rate_hz, rate_name) = match (spec.sample_rate_hz.or(campaign_rate_hz), time_rate_hz)
    {
        (Some(fs), _) => (fs, "sample_rate_hz"),
        (None, Some(fs)) => (fs, "the test's time column"),
        // no rate yet: no frequency is above a Nyquist frequency not known
        (None, None) => (f64::INFINITY, ""),
    };
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
                "{f} Hz is above the Nyquist frequency {} Hz of {rate_name}",
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
                "[{lo}, {hi}]: the band goes above the Nyquist frequency {} Hz of {rate_name}",
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
