//! A synthesised campaign on disk: campaign.toml and the CSVs, with the truth and the
//! synthesis options beside them.

use super::*;
use crate::campaign::format::{write_campaign, CampaignError};
use crate::campaign::Campaign;
use crate::output::atomic_write;
use crate::params::Params;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// What `synthesis.toml` holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SynthesisInfo {
    pub generator: String,
    pub sample_rate_hz: f64,
    pub tests: Vec<String>,
    pub options: SynthOptions,
}

/// Write a synthesised campaign into `dir`: campaign.toml and the CSVs, plus
/// [`TRUTH_FILE`] (the full parameters used) and [`SYNTHESIS_FILE`] (seed, noise
/// levels, options). Identification must never read the last two.
pub fn write_synthetic(
    campaign: &Campaign,
    params: &Params,
    opts: &SynthOptions,
    dir: &Path,
) -> Result<(), CampaignError> {
    write_campaign(campaign, dir)?;
    let truth = dir.join(TRUTH_FILE);
    let text = format!(
        "# The parameters this synthetic campaign was made with (the truth).\n\
         # Tests may compare identified values with it; identification must never read it.\n{}",
        params.to_toml_string()
    );
    atomic_write(&truth, text.as_bytes())?;
    let info = SynthesisInfo {
        generator: format!("shaketable {} campaign synth", env!("CARGO_PKG_VERSION")),
        sample_rate_hz: campaign.info.sample_rate_hz,
        tests: campaign.info.tests.iter().map(|t| t.name.clone()).collect(),
        options: opts.clone(),
    };
    let syn = dir.join(SYNTHESIS_FILE);
    let text = format!(
        "# How this synthetic campaign was made (seed, sensor noise RMS, options).\n{}",
        toml::to_string(&info).map_err(|e| CampaignError::Invalid {
            file: syn.display().to_string(),
            message: e.to_string(),
        })?
    );
    atomic_write(&syn, text.as_bytes())?;
    Ok(())
}

/// Synthesise and write in one go; returns the campaign (with `dir` set).
pub fn synthesise_to_dir(
    params: &Params,
    opts: &SynthOptions,
    dir: &Path,
    progress: Option<Progress>,
) -> Result<Campaign, SynthError> {
    opts.validate()?;
    let mut c = synthesise_program(params, &selected_program(opts), opts, progress)?;
    write_synthetic(&c, params, opts, dir)?;
    c.dir = dir.to_path_buf();
    Ok(c)
}
