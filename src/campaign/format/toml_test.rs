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
    let name = test_name(lines, t, off, index)?;
    let entry = TestEntry {
        lines,
        t,
        off,
        name: Some(name.as_str()),
    };
    let (file, file_off) = entry.file()?;
    let kind = entry.kind()?;
    let control = entry.control()?;
    let mut spec = TestSpec::new(name.clone(), file, kind, control);
    // the test's own rate, checked like the campaign's; its Nyquist bounds the test
    spec.sample_rate_hz = entry.optional("sample_rate_hz", SAMPLE_RATE_HZ)?;
    let nyquist = Nyquist::of(spec.sample_rate_hz.or(campaign_rate_hz), time_rate_hz);
    entry.read_levels(&mut spec, &nyquist)?;
    if let Some(v) = lookup(t, "band_hz") {
        spec.band_hz = Some(entry.band(v, &nyquist)?);
    }
    entry.check_kind_keys(&spec)?;
    if let Some(v) = lookup(t, "controller") {
        spec.controller = read_override(lines, v, &name)?;
    }
    Ok((spec, file_off))
}

/// The test's `name`, required and not blank; an error before the name is known names
/// the test by its place, `#N (unnamed)`.
fn test_name(
    lines: &Lines,
    t: &RawTable,
    off: usize,
    index: usize,
) -> Result<String, CampaignError> {
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
    if name.trim().is_empty() {
        return Err(lines.err(Some(off), Some(name), Some("name"), "test name is empty"));
    }
    Ok(name.to_string())
}

/// The rate whose Nyquist frequency bounds a test's frequencies and band, and what
/// gives it (named in errors).
struct Nyquist {
    sample_rate_hz: f64,
    rate_name: &'static str,
}

impl Nyquist {
    /// The test's own or the campaign's rate, else its time column's; neither known: no
    /// bound yet (infinite).
    fn of(declared_hz: Option<f64>, time_rate_hz: Option<f64>) -> Nyquist {
        let (sample_rate_hz, rate_name) = match (declared_hz, time_rate_hz) {
            (Some(fs), _) => (fs, "sample_rate_hz"),
            (None, Some(fs)) => (fs, "the test's time column"),
            // no rate yet: no frequency is above a Nyquist frequency not known
            (None, None) => (f64::INFINITY, ""),
        };
        Nyquist {
            sample_rate_hz,
            rate_name,
        }
    }

    /// Half the rate, Hz.
    fn frequency_hz(&self) -> f64 {
        self.sample_rate_hz / 2.0
    }
}

/// One `[[test]]` table while it is read: where it is and the test's name, for errors.
struct TestEntry<'a> {
    lines: &'a Lines<'a>,
    t: &'a RawTable,
    off: usize,
    name: Option<&'a str>,
}

impl<'a> TestEntry<'a> {
    /// An error at `off` (the entry's header when `None`) on `key` of this test.
    fn err(&self, off: Option<usize>, key: &str, message: impl Into<String>) -> CampaignError {
        self.lines.err(off, self.name, Some(key), message)
    }

    /// A required string key and the offset of its value.
    fn required(&self, key: &str, what: &str) -> Result<(&'a str, usize), CampaignError> {
        required_string(self.lines, self.t, self.off, self.name, key, what)
    }

    /// An optional number key, checked against `check`.
    fn optional(&self, key: &str, check: Bound) -> Result<Option<f64>, CampaignError> {
        lookup(self.t, key)
            .map(|v| number(self.lines, v, self.name, key, check))
            .transpose()
    }

    /// The test's `file`: required, not blank, lexically inside the campaign folder;
    /// with the offset of its value.
    fn file(&self) -> Result<(&'a str, usize), CampaignError> {
        let (file, file_off) = self.required("file", "the CSV of the test")?;
        if file.trim().is_empty() {
            return Err(self.err(Some(file_off), "file", "file name is empty"));
        }
        check_test_file(self.lines, file, file_off, self.name)?;
        Ok((file, file_off))
    }

    /// The test's `kind`: random, sine, triangle or record.
    fn kind(&self) -> Result<TestKind, CampaignError> {
        let (kind_s, kind_off) = self.required("kind", "random | sine | triangle | record")?;
        match kind_s {
            "random" => Ok(TestKind::Random),
            "sine" => Ok(TestKind::Sine),
            "triangle" => Ok(TestKind::Triangle),
            "record" => Ok(TestKind::Record),
            other => Err(self.err(
                Some(kind_off),
                "kind",
                format!("unknown kind `{other}`; expected random | sine | triangle | record"),
            )),
        }
    }

    /// The test's `control`: displacement or acceleration.
    fn control(&self) -> Result<Control, CampaignError> {
        let (control_s, control_off) = self.required("control", "displacement | acceleration")?;
        match control_s {
            "displacement" => Ok(Control::Displacement),
            "acceleration" => Ok(Control::Acceleration),
            other => Err(self.err(
                Some(control_off),
                "control",
                format!("unknown control `{other}`; expected displacement | acceleration"),
            )),
        }
    }

    /// `rms` (in the unit of the test's control), `frequency_hz` and `amplitude_m`, each
    /// optional here; a frequency must be below the test's Nyquist frequency.
    fn read_levels(&self, spec: &mut TestSpec, nyquist: &Nyquist) -> Result<(), CampaignError> {
        let level = match spec.control {
            Control::Displacement => DISPLACEMENT_M,
            Control::Acceleration => ACCELERATION_M_S2,
        };
        spec.rms = self.optional("rms", level)?;
        spec.frequency_hz = self.optional("frequency_hz", TEST_FREQUENCY_HZ)?;
        spec.amplitude_m = self.optional("amplitude_m", DISPLACEMENT_M)?;
        if let Some(f) = spec.frequency_hz.filter(|&f| f > nyquist.frequency_hz()) {
            let rate_name = nyquist.rate_name;
            let v = lookup(self.t, "frequency_hz").map(|v| v.span().start);
            return Err(self.err(
                v,
                "frequency_hz",
                format!(
                    "{f} Hz is above the Nyquist frequency {} Hz of {rate_name}",
                    nyquist.frequency_hz()
                ),
            ));
        }
        Ok(())
    }

    /// `band_hz = [low, high]`: two finite numbers, `0 <= low < high`, a low edge above 0
    /// no lower than the lowest test frequency, the high edge at most the Nyquist frequency.
    fn band(&self, v: &Spanned<toml::Value>, nyquist: &Nyquist) -> Result<[f64; 2], CampaignError> {
        let bad = |m: String| self.err(Some(v.span().start), "band_hz", m);
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
        if hi > nyquist.frequency_hz() {
            let rate_name = nyquist.rate_name;
            return Err(bad(format!(
                "[{lo}, {hi}]: the band goes above the Nyquist frequency {} Hz of {rate_name}",
                nyquist.frequency_hz()
            )));
        }
        Ok([lo, hi])
    }

    /// The keys the test's kind needs: a random test its level and band, a sine or
    /// triangle its frequency and amplitude; a record test nothing more.
    fn check_kind_keys(&self, spec: &TestSpec) -> Result<(), CampaignError> {
        let missing = |key: &str, message: String| Err(self.err(Some(self.off), key, message));
        match spec.kind {
            TestKind::Random => {
                let why = "a random test needs its level (m RMS for displacement control, m/s^2 RMS for acceleration control)";
                if spec.rms.is_none() {
                    return missing("rms", format!("required key is missing ({why})"));
                }
                if spec.band_hz.is_none() {
                    return missing(
                        "band_hz",
                        "required key is missing (a random test needs its band [low, high] in Hz)"
                            .to_string(),
                    );
                }
            }
            TestKind::Sine | TestKind::Triangle => {
                let k = if spec.kind == TestKind::Sine {
                    "sine"
                } else {
                    "triangle"
                };
                if spec.frequency_hz.is_none() {
                    return missing(
                        "frequency_hz",
                        format!("required key is missing (a {k} test needs its frequency in Hz)"),
                    );
                }
                if spec.amplitude_m.is_none() {
                    return missing(
                        "amplitude_m",
                        format!("required key is missing (a {k} test needs its displacement amplitude in m)"),
                    );
                }
            }
            // any reference: nothing more is needed
            TestKind::Record => {}
        }
        Ok(())
    }
}
