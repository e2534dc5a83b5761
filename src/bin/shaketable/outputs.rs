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
            output::check_file(f, force, &inputs)?;
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
        })
    }

    fn write(&self, path: &Option<PathBuf>, text: &str) -> anyhow::Result<()> {
        if let Some(p) = path {
            output::write_file(p, text.as_bytes(), self.force, &self.inputs)?;
            println!("wrote {}", p.display());
        }
        Ok(())
    }

    /// Write the JSON text (if `--json`).
    pub fn json(&self, text: &str) -> anyhow::Result<()> {
        self.write(&self.json, text)
    }

    /// Write the parameter file text (if `--params-out`).
    pub fn params(&self, text: &str) -> anyhow::Result<()> {
        self.write(&self.params_out, text)
    }

    /// Build the report (if `--report`) in a temporary folder, then put it in place.
    pub fn report(&self, build: impl FnOnce(&Path) -> anyhow::Result<()>) -> anyhow::Result<()> {
        let Some(plan) = &self.report else {
            return Ok(());
        };
        let dir = plan.target();
        let context = || format!("writing the report {}", dir.display());
        let staging = plan.stage().with_context(context)?;
        build(staging.path()).with_context(context)?;
        staging.commit().with_context(context)?;
        println!("wrote {}", dir.join("index.html").display());
        Ok(())
    }
}
