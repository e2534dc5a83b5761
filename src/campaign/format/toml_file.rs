//! campaign.toml: parsing with the line, test and key of every error, and the
//! plausible physical ranges of its values.

use super::toml_gains::{read_controller, rename_key};
use super::toml_test::read_test;
use super::toml_values::*;
use super::*;

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
///
/// In a laboratory's form a test may take its rate from a mapped time column instead of
/// `sample_rate_hz` (campaign-format.md, "What is required": a time column, or
/// `sample_rate_hz`): its plan's rate is then `None`, and so are the Nyquist checks of its
/// frequencies until the rate is known ([`parse_with_time_rates`]). When campaign.toml
/// gives no `sample_rate_hz` at all, the info's is NaN until the records are read.
pub fn parse_campaign_toml_planned(
    text: &str,
    file: &str,
    default_name: &str,
) -> Result<(CampaignInfo, Vec<usize>, Vec<ReadPlan>), CampaignError> {
    parse_with_time_rates(text, file, default_name, &[])
}

/// [`parse_campaign_toml_planned`] with the rates read from the time columns of the tests
/// that give none (`time_rates[i]` for test `i`; empty: none known yet): the tests'
/// frequencies and bands are checked against them.
pub(super) fn parse_with_time_rates(
    text: &str,
    file: &str,
    default_name: &str,
    time_rates: &[Option<f64>],
) -> Result<(CampaignInfo, Vec<usize>, Vec<ReadPlan>), CampaignError> {
    // classic Mac line ends (a lone CR) read as line ends; offsets are unchanged
    let text = lone_cr_to_lf(text);
    let text: &str = &text;
    let lines = Lines { text, file };
    let doc = parse_doc(&lines)?;
    let name = campaign_name(&lines, &doc, default_name)?;
    let sample_rate_hz = doc
        .sample_rate_hz
        .as_ref()
        .map(|v| number(&lines, v, None, "sample_rate_hz", SAMPLE_RATE_HZ))
        .transpose()?;
    let geometry = match &doc.geometry {
        Some(g) => read_geometry(&lines, g)?,
        None => Geometry::default(),
    };
    let controller = match &doc.controller {
        Some(c) => read_controller(&lines, c)?,
        None => ControllerOverride::default(),
    };
    let raw_tests = test_entries(&lines, &doc)?;
    let wide = CampaignWide::read(&lines, &doc, raw_tests, sample_rate_hz)?;
    let mut read = TestsRead::new(&lines, &wide);
    for (i, raw) in raw_tests.iter().enumerate() {
        read.add(raw, i, time_rates.get(i).copied().flatten())?;
    }
    Ok((
        CampaignInfo {
            name,
            sample_rate_hz: sample_rate_hz.unwrap_or(f64::NAN),
            geometry,
            controller,
            tests: read.tests,
        },
        read.file_lines,
        read.plans,
    ))
}

/// The TOML document of campaign.toml; a syntax error names its line.
fn parse_doc(lines: &Lines) -> Result<RawDoc, CampaignError> {
    toml::from_str(lines.text).map_err(|e| {
        let msg = e.message().trim().to_string();
        lines.err(
            e.span().map(|s| s.start),
            None,
            None,
            format!("not valid TOML: {msg}"),
        )
    })
}

/// The campaign's `name`, a string; `default_name` when campaign.toml gives none.
fn campaign_name(lines: &Lines, doc: &RawDoc, default_name: &str) -> Result<String, CampaignError> {
    match &doc.name {
        Some(v) => match v.get_ref() {
            toml::Value::String(s) => Ok(s.clone()),
            other => Err(lines.err(
                Some(v.span().start),
                None,
                Some("name"),
                format!("expected a string, found {}", type_name(other)),
            )),
        },
        None => Ok(default_name.to_string()),
    }
}

/// `[geometry]`: every key optional (one not given is unknown), each checked against
/// its plausible range and named `geometry.<key>` in errors.
fn read_geometry(lines: &Lines, g: &Spanned<RawTable>) -> Result<Geometry, CampaignError> {
    let get = |key: &str, bound: Bound| -> Result<Option<f64>, CampaignError> {
        lookup(g.get_ref(), key)
            .map(|v| {
                number(lines, v, None, key, bound)
                    .map_err(|e| rename_key(e, &format!("geometry.{key}")))
            })
            .transpose()
    };
    Ok(Geometry {
        piston_area_m2: get("piston_area_m2", PISTON_AREA_M2)?,
        total_oil_volume_m3: get("total_oil_volume_m3", OIL_VOLUME_M3)?,
        supply_pressure_pa: get("supply_pressure_pa", SUPPLY_PRESSURE_PA)?,
        flow_gain_m3_s: get("flow_gain_m3_s", FLOW_GAIN_M3_S)?,
    })
}

/// The `[[test]]` entries: at least one.
fn test_entries<'d>(
    lines: &Lines,
    doc: &'d RawDoc,
) -> Result<&'d [Spanned<RawTable>], CampaignError> {
    match &doc.test {
        Some(t) if !t.get_ref().is_empty() => Ok(t.get_ref()),
        Some(t) => Err(lines.err(
            Some(t.span().start),
            None,
            Some("test"),
            "the campaign has no tests",
        )),
        None => Err(lines.err(
            None,
            None,
            Some("test"),
            "the campaign has no [[test]] entries",
        )),
    }
}

/// What every test's plan starts from: the campaign's rate, `[read]` and `[columns]`,
/// and whether campaign.toml is in a laboratory's form (any `read` or `columns`).
struct CampaignWide {
    sample_rate_hz: Option<f64>,
    read: ReadOverride,
    columns: BTreeMap<String, ColumnEntry>,
    lab_form: bool,
}

impl CampaignWide {
    /// Read `[read]` and `[columns]`; outside a laboratory's form `sample_rate_hz` is
    /// required (the project's own form has no time base without it).
    fn read(
        lines: &Lines,
        doc: &RawDoc,
        raw_tests: &[Spanned<RawTable>],
        sample_rate_hz: Option<f64>,
    ) -> Result<CampaignWide, CampaignError> {
        let read = match &doc.read {
            Some(v) => toml_layout::read_options(lines, v.span().start, None, v.get_ref())?,
            None => ReadOverride::default(),
        };
        let columns = match &doc.columns {
            Some(v) => toml_layout::columns(lines, v.span().start, None, v.get_ref())?,
            None => BTreeMap::new(),
        };
        let lab_form = doc.read.is_some()
            || doc.columns.is_some()
            || raw_tests.iter().any(|t| {
                lookup(t.get_ref(), "read").is_some() || lookup(t.get_ref(), "columns").is_some()
            });
        if sample_rate_hz.is_none() && !lab_form {
            return Err(lines.err(
                None,
                None,
                Some("sample_rate_hz"),
                "required key is missing (the sampling rate of every record, Hz)",
            ));
        }
        Ok(CampaignWide {
            sample_rate_hz,
            read,
            columns,
            lab_form,
        })
    }
}

/// The tests read so far, with their plans, the lines of their `file` keys and of their
/// `[[test]]` headers (for the duplicate checks' messages).
struct TestsRead<'a> {
    lines: &'a Lines<'a>,
    wide: &'a CampaignWide,
    tests: Vec<TestSpec>,
    plans: Vec<ReadPlan>,
    file_lines: Vec<usize>,
    header_lines: Vec<usize>,
}

impl<'a> TestsRead<'a> {
    /// None read yet, each to be planned from `wide`.
    fn new(lines: &'a Lines<'a>, wide: &'a CampaignWide) -> Self {
        TestsRead {
            lines,
            wide,
            tests: Vec::new(),
            plans: Vec::new(),
            file_lines: Vec::new(),
            header_lines: Vec::new(),
        }
    }

    /// Read test `index` and its plan, check it has a time base and is not a duplicate,
    /// and keep it.
    fn add(
        &mut self,
        raw: &Spanned<RawTable>,
        index: usize,
        time_rate: Option<f64>,
    ) -> Result<(), CampaignError> {
        let (lines, wide) = (self.lines, self.wide);
        let (spec, file_off) = read_test(lines, raw, index, wide.sample_rate_hz, time_rate)?;
        let here = lines.line(raw.span().start);
        let mut plan = test_plan(lines, raw, &spec, wide)?;
        plan.lab_form = wide.lab_form;
        if plan.sample_rate_hz.is_none() && !plan.columns.contains_key("time_s") {
            return Err(lines.err(
                Some(raw.span().start),
                Some(&spec.name),
                Some("sample_rate_hz"),
                "required key is missing: the test has no time base; give `sample_rate_hz` \
                 (campaign-wide or the test's own), or map its time column as `time_s` in \
                 [columns] (e.g. `time_s = { column = \"Time_ms\", scale = 0.001 }`)",
            ));
        }
        self.check_name(raw, &spec)?;
        self.check_file(&spec, &plan, file_off)?;
        self.plans.push(plan);
        self.header_lines.push(here);
        self.file_lines.push(lines.line(file_off));
        self.tests.push(spec);
        Ok(())
    }

    /// A new test's name is not taken by an earlier test.
    fn check_name(&self, raw: &Spanned<RawTable>, spec: &TestSpec) -> Result<(), CampaignError> {
        match self.tests.iter().position(|t| t.name == spec.name) {
            Some(j) => Err(self.lines.err(
                Some(raw.span().start),
                Some(&spec.name),
                Some("name"),
                format!(
                    "duplicate test name: already used by the test at line {}",
                    self.header_lines[j]
                ),
            )),
            None => Ok(()),
        }
    }

    /// A new test's file is not an earlier test's (`file_off`: its value's offset).
    fn check_file(
        &self,
        spec: &TestSpec,
        plan: &ReadPlan,
        file_off: usize,
    ) -> Result<(), CampaignError> {
        let lab_form = self.wide.lab_form;
        // one file may hold several tests in a laboratory's form, each with its columns
        let same = |j: &usize| {
            normalise_relative(&self.tests[*j].file) == normalise_relative(&spec.file)
                && (!lab_form || self.plans[*j].columns == plan.columns)
        };
        match (0..self.tests.len()).find(same) {
            Some(j) => Err(self.lines.err(
                Some(file_off),
                Some(&spec.name),
                Some("file"),
                format!(
                    "`{}` is already the file of test `{}` (line {}){}",
                    spec.file,
                    self.tests[j].name,
                    self.file_lines[j],
                    if lab_form {
                        " with the same columns"
                    } else {
                        ""
                    }
                ),
            )),
            None => Ok(()),
        }
    }
}

/// How test `spec`'s file is read: `[read]` and `[columns]` with the test's overrides.
fn test_plan(
    lines: &Lines,
    raw: &Spanned<RawTable>,
    spec: &TestSpec,
    wide: &CampaignWide,
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
    let columns = merge_columns(&wide.columns, &test_columns)
        .map_err(|m| lines.err(Some(columns_off), name, Some("columns"), m))?;
    Ok(ReadPlan {
        read: ReadOptions::default().merged(&wide.read).merged(&test_read),
        columns,
        lab_form: false,
        sample_rate_hz: spec.sample_rate_hz.or(wide.sample_rate_hz),
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
        assert_eq!(plans[0].sample_rate_hz, Some(1000.0));
        assert_eq!(plans[0].own_rate_line, Some(10));
        assert_eq!(
            (plans[1].sample_rate_hz, plans[1].own_rate_line),
            (Some(512.0), None)
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
