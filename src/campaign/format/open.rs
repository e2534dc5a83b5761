//! Reading a campaign folder: campaign.toml, every test file located inside the folder,
//! the records read under their plans, and the rates of the tests whose time base is a
//! time column rather than `sample_rate_hz` (campaign-format.md, "What is required").

use super::toml_file::parse_with_time_rates;
use super::*;

/// campaign.toml read and parsed: its text, info, the line of each test's `file` key and
/// each test's plan.
struct Toml {
    file: String,
    text: String,
    info: CampaignInfo,
    file_lines: Vec<usize>,
    plans: Vec<ReadPlan>,
}

impl Toml {
    fn read(root: &Path, dir: &Path) -> Result<Toml, CampaignError> {
        let (text, file) = read_toml_text(root, dir)?;
        let (info, file_lines, plans) = parse_campaign_toml_planned(&text, &file, &dir_name(dir))?;
        Ok(Toml {
            file,
            text,
            info,
            file_lines,
            plans,
        })
    }

    /// Whether some test takes its rate from its time column (campaign.toml gives none).
    fn rates_from_time(&self) -> bool {
        self.plans.iter().any(|p| p.sample_rate_hz.is_none())
    }

    /// Test `i`'s file, at `real`, read under its plan; with the record's rate.
    fn read_test(
        &self,
        dir: &Path,
        real: &Path,
        i: usize,
    ) -> Result<(Record, Sources, f64), CampaignError> {
        let (spec, plan) = (&self.info.tests[i], &self.plans[i]);
        let shown = display(&dir.join(&spec.file));
        read_test_file(real, &shown, plan, &rate_source(plan, &self.file, spec))
    }

    /// The rates read from the time columns (`rates[i]` of test `i`, `None` where unread)
    /// given to the tests campaign.toml gives none: each takes it as its own, the first
    /// becomes the campaign's default when campaign.toml has none, and the tests'
    /// frequencies and bands are checked against them (their Nyquist frequencies).
    fn settle_time_rates(
        &mut self,
        dir: &Path,
        rates: &[Option<f64>],
    ) -> Result<(), CampaignError> {
        let from_time: Vec<Option<f64>> = self
            .plans
            .iter()
            .zip(rates)
            .map(|(p, r)| r.filter(|_| p.sample_rate_hz.is_none()))
            .collect();
        if from_time.iter().all(Option::is_none) {
            return Ok(());
        }
        // the same text again with the rates known: errors name their lines as before
        parse_with_time_rates(&self.text, &self.file, &dir_name(dir), &from_time)?;
        for (spec, fs) in self.info.tests.iter_mut().zip(&from_time) {
            if let Some(fs) = fs {
                spec.sample_rate_hz = Some(*fs);
            }
        }
        if self.info.sample_rate_hz.is_nan() {
            self.info.sample_rate_hz = from_time
                .iter()
                .flatten()
                .copied()
                .next()
                .unwrap_or(f64::NAN);
        }
        Ok(())
    }

    /// The records of the tests whose rate comes from their time column, read only to
    /// settle those rates ([`Self::settle_time_rates`]); `rates` holds those already read
    /// (`None` where not), which are not read again. `real`: the located files.
    fn settle_unread_rates(
        &mut self,
        dir: &Path,
        real: &[PathBuf],
        mut rates: Vec<Option<f64>>,
    ) -> Result<(), CampaignError> {
        for (i, real) in real.iter().enumerate() {
            if self.plans[i].sample_rate_hz.is_none() && rates[i].is_none() {
                rates[i] = Some(self.read_test(dir, real, i)?.2);
            }
        }
        self.settle_time_rates(dir, &rates)
    }

    fn locate(&self, root: &Path, dir: &Path) -> Result<Vec<PathBuf>, CampaignError> {
        locate_test_files(
            root,
            dir,
            &self.info,
            &self.file_lines,
            &self.plans,
            &self.file,
        )
    }
}

/// Read and check `dir/campaign.toml`; records are opened only when a test takes its
/// rate from its time column (campaign.toml gives it none), to read that rate.
pub fn read_campaign_info(dir: &Path) -> Result<CampaignInfo, CampaignError> {
    let root = campaign_root(dir)?;
    let mut toml = Toml::read(&root, dir)?;
    if toml.rates_from_time() {
        let real = toml.locate(&root, dir)?;
        let unread = vec![None; real.len()];
        toml.settle_unread_rates(dir, &real, unread)?;
    }
    Ok(toml.info)
}

/// Where each test's file is, checked before any record is read: inside the campaign
/// folder after resolving symlinks, a regular file within [`MAX_RECORD_BYTES`], and not
/// the file of another test nor campaign.toml (same device and inode: symlinks and hard
/// links included). Errors point at the test's `file` key.
fn locate_test_files(
    root: &Path,
    dir: &Path,
    info: &CampaignInfo,
    file_lines: &[usize],
    plans: &[ReadPlan],
    toml_file: &str,
) -> Result<Vec<PathBuf>, CampaignError> {
    use std::os::unix::fs::MetadataExt;
    let identity = |m: &std::fs::Metadata| (m.dev(), m.ino());
    let toml_id = std::fs::metadata(dir.join("campaign.toml"))
        .ok()
        .map(|m| identity(&m));
    let mut seen: Vec<((u64, u64), usize)> = Vec::new();
    let mut paths = Vec::with_capacity(info.tests.len());
    for (i, (spec, &line)) in info.tests.iter().zip(file_lines).enumerate() {
        let err = |message: String| CampaignError::Toml {
            file: toml_file.to_string(),
            line: Some(line),
            test: Some(spec.name.clone()),
            key: Some("file".to_string()),
            message,
        };
        let path = dir.join(&spec.file);
        let shown = display(&path);
        let real = match resolve_inside(root, dir, &spec.file) {
            Ok(real) => real,
            Err(Some(real)) => {
                return Err(err(format!(
                    "`{}` resolves to {}, outside the campaign folder {}; a test file must be inside it (not opened)",
                    spec.file,
                    real.display(),
                    root.display()
                )))
            }
            Err(None) => path.clone(),
        };
        let meta =
            std::fs::metadata(&real).map_err(|e| err(format!("cannot read {shown}: {e}")))?;
        if !meta.file_type().is_file() || meta.len() > MAX_RECORD_BYTES {
            let r = read_regular(&real, MAX_RECORD_BYTES, "largest plausible record");
            let why = r.err().map_or_else(String::new, |r| r.to_string());
            return Err(err(format!("{shown} {why}")));
        }
        let id = identity(&meta);
        if Some(id) == toml_id {
            return Err(err(format!(
                "{shown} is campaign.toml itself, not a record"
            )));
        }
        // a laboratory's file may hold several tests, each read from its own columns
        let same_source = |j: usize| !plans[i].lab_form || plans[j].columns == plans[i].columns;
        if let Some(&(_, j)) = seen.iter().find(|(s, j)| *s == id && same_source(*j)) {
            return Err(err(format!(
                "{shown} is the same file as `{}` of test `{}` (line {}): one file per test",
                info.tests[j].file, info.tests[j].name, file_lines[j]
            )));
        }
        seen.push((id, i));
        paths.push(real);
    }
    Ok(paths)
}

/// Where test `spec`'s rate comes from, for a time column that disagrees with it:
/// campaign.toml, with the line, test and key of the test's own `sample_rate_hz` when it
/// has one (campaign-format.md, "Bad input in this form").
fn rate_source(plan: &ReadPlan, toml_file: &str, spec: &TestSpec) -> String {
    match plan.own_rate_line {
        Some(line) => format!(
            "{toml_file} line {line} (test `{}`, key `sample_rate_hz`)",
            spec.name
        ),
        None => toml_file.to_string(),
    }
}

/// Read a whole campaign: campaign.toml and every record it lists, in parallel.
pub fn read_campaign(dir: &Path) -> Result<Campaign, CampaignError> {
    let root = campaign_root(dir)?;
    let mut toml = Toml::read(&root, dir)?;
    let real = toml.locate(&root, dir)?;
    let results: Vec<Result<(Record, Sources, f64), CampaignError>> = real
        .par_iter()
        .enumerate()
        .map(|(i, real)| toml.read_test(dir, real, i))
        .collect();
    let mut records = Vec::with_capacity(results.len());
    let mut rates = Vec::with_capacity(results.len());
    let mut sources = crate::campaign::provenance::SourcesByTest::new();
    for (r, spec) in results.into_iter().zip(&toml.info.tests) {
        let (record, s, fs) = r?;
        records.push(record);
        rates.push(Some(fs));
        sources.insert(spec.name.clone(), s);
    }
    toml.settle_time_rates(dir, &rates)?;
    Ok(Campaign {
        dir: dir.to_path_buf(),
        info: toml.info,
        records,
        sources,
    })
}

/// One test of a campaign, by name: the campaign's description and the test's record,
/// read under its plan (every test file is located and checked; only this one is read,
/// and those whose rate comes from their time column).
pub fn read_campaign_test(dir: &Path, name: &str) -> Result<(CampaignInfo, Record), CampaignError> {
    let root = campaign_root(dir)?;
    let mut toml = Toml::read(&root, dir)?;
    let Some(i) = toml.info.tests.iter().position(|t| t.name == name) else {
        let names: Vec<&str> = toml.info.tests.iter().map(|t| t.name.as_str()).collect();
        return Err(CampaignError::Toml {
            file: toml.file,
            line: None,
            test: Some(name.to_string()),
            key: None,
            message: format!(
                "no such test; the campaign's tests are {}",
                names.join(", ")
            ),
        });
    };
    let real = toml.locate(&root, dir)?;
    let (record, _, fs) = toml.read_test(dir, &real[i], i)?;
    let mut rates = vec![None; real.len()];
    rates[i] = Some(fs);
    toml.settle_unread_rates(dir, &real, rates)?;
    Ok((toml.info, record))
}
