//! The outputs of `identify` and `diagnose` (`--json`, `--params-out`, `--report`),
//! checked by the safe-write rules of [`shaketable::output`] before the long work.

use anyhow::Context;
use shaketable::campaign::Campaign;
use shaketable::output::{self, DirPlan, Inputs};
use std::path::{Path, PathBuf};

/// Where a command's results go, already checked.
pub struct Outputs {
    json: Option<PathBuf>,
    params_out: Option<PathBuf>,
    report: Option<DirPlan>,
    force: bool,
    inputs: Inputs,
    /// `diagnose --baseline-out`: the refined baseline the gain is measured against.
    baseline_out: Option<PathBuf>,
}

/// Every file a campaign run reads: campaign.toml and the records.
pub fn campaign_inputs(c: &Campaign) -> Inputs {
    let mut inputs = Inputs::new();
    inputs.add(&c.dir.join("campaign.toml"));
    for t in &c.info.tests {
        inputs.add(&c.dir.join(&t.file));
    }
    inputs
}

impl Outputs {
    /// Check the outputs of `command` against the rules (and against each other).
    pub fn check(
        command: &str,
        json: Option<&Path>,
        params_out: Option<&Path>,
        report: Option<&Path>,
        force: bool,
        inputs: Inputs,
    ) -> anyhow::Result<Self> {
        let files: Vec<&Path> = json.iter().chain(params_out.iter()).copied().collect();
        output::check_distinct(&files)?;
        for f in &files {
            // a file inside the report folder is part of the report (checked with it)
            if !report.is_some_and(|r| in_folder(f, r)) {
                output::check_file(f, force, &inputs)?;
            }
        }
        let report = match report {
            Some(dir) => Some(
                output::plan_dir(dir, &format!("{command} --report"), force, &inputs)
                    .with_context(|| format!("--report {}", dir.display()))?,
            ),
            None => None,
        };
        Ok(Outputs {
            json: json.map(Path::to_path_buf),
            params_out: params_out.map(Path::to_path_buf),
            report,
            force,
            inputs,
            baseline_out: None,
        })
    }

    /// Add `diagnose --baseline-out FILE`, checked by the same rules (distinct from the
    /// other files, never over an input, replaced only with `--force`); outside the report
    /// folder, which is replaced whole.
    pub fn with_baseline_out(mut self, path: Option<&Path>) -> anyhow::Result<Self> {
        let Some(path) = path else { return Ok(self) };
        let others: Vec<&Path> = [&self.json, &self.params_out]
            .into_iter()
            .flatten()
            .map(PathBuf::as_path)
            .chain(std::iter::once(path))
            .collect();
        output::check_distinct(&others)?;
        if let Some(r) = &self.report {
            if in_folder(path, r.target()) {
                anyhow::bail!(
                    "--baseline-out {}: inside the --report folder, which is replaced whole; write it elsewhere",
                    path.display()
                );
            }
        }
        output::check_file(path, self.force, &self.inputs)?;
        self.baseline_out = Some(path.to_path_buf());
        Ok(self)
    }

    /// Write the `--baseline-out` file, when one was asked for.
    pub fn write_baseline(&self, text: &str) -> anyhow::Result<()> {
        if let Some(p) = &self.baseline_out {
            output::write_file(p, text.as_bytes(), self.force, &self.inputs)?;
            println!("wrote {}", p.display());
        }
        Ok(())
    }

    /// Write the JSON text (for `--json`), the parameter file (for `--params-out`) and the
    /// report (`--report`, built by `build` in a temporary folder, then put in place).
    /// JSON and parameter files inside the report folder are written with the report.
    pub fn write(
        &self,
        json: &str,
        params: &str,
        build: impl FnOnce(&Path) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        let files = [(&self.json, json), (&self.params_out, params)];
        let mut with_report = Vec::new();
        for (path, text) in files {
            let Some(p) = path else { continue };
            match &self.report {
                Some(r) if in_folder(p, r.target()) => with_report.push((p, text)),
                _ => {
                    output::write_file(p, text.as_bytes(), self.force, &self.inputs)?;
                    println!("wrote {}", p.display());
                }
            }
        }
        let Some(plan) = &self.report else {
            return Ok(());
        };
        let dir = plan.target();
        let context = || format!("writing the report {}", dir.display());
        let staging = plan.stage().with_context(context)?;
        build(staging.path()).with_context(context)?;
        for (p, text) in &with_report {
            let name = p.file_name().unwrap_or_default();
            output::atomic_write(&staging.path().join(name), text.as_bytes())?;
        }
        staging.commit().with_context(context)?;
        for (p, _) in &with_report {
            println!("wrote {}", p.display());
        }
        println!("wrote {}", dir.join("index.html").display());
        Ok(())
    }
}

/// Whether `file` names an entry directly inside `folder` (lexically, made absolute).
fn in_folder(file: &Path, folder: &Path) -> bool {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    file.parent().map(abs) == Some(abs(folder)) && file.file_name().is_some()
}
