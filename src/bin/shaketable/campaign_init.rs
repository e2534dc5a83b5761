//! `shaketable campaign init DIR`: a campaign.toml skeleton for a laboratory's files
//! (library: [`shaketable::campaign::init`]). Never overwrites an existing campaign.toml.

use anyhow::Context;
use shaketable::campaign::init::{skeleton, sniff_dir};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct InitArgs {
    /// The folder holding the laboratory's recordings.
    dir: PathBuf,
}

pub fn run_init(a: InitArgs) -> anyhow::Result<()> {
    let path = a.dir.join("campaign.toml");
    if std::fs::symlink_metadata(&path).is_ok() {
        anyhow::bail!(
            "{}: exists; campaign init never overwrites it (move it away to start again)",
            path.display()
        );
    }
    let (found, skipped) =
        sniff_dir(&a.dir).with_context(|| format!("{}: cannot list", a.dir.display()))?;
    if found.is_empty() {
        let why: Vec<String> = skipped
            .iter()
            .map(|s| format!("\n  skipped {}: {}", s.file, s.why))
            .collect();
        anyhow::bail!(
            "{}: no file with rows of numbers or MATLAB signals found ({} skipped){}",
            a.dir.display(),
            skipped.len(),
            why.concat()
        );
    }
    let name = a
        .dir
        .canonicalize()
        .ok()
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "campaign".into());
    let text = skeleton(&name, &found, &skipped);
    // create_new: a campaign.toml made between the check and here is not replaced either
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&path)
        .with_context(|| format!("{}: cannot create", path.display()))?;
    f.write_all(text.as_bytes())
        .with_context(|| format!("{}: cannot write", path.display()))?;
    println!(
        "wrote {}: {} file(s) described, {} skipped; map the columns in [columns], set each test's kind and control, then `shaketable campaign check {}`",
        path.display(),
        found.len(),
        skipped.len(),
        a.dir.display()
    );
    for s in &skipped {
        println!("  skipped {}: {}", s.file, s.why);
    }
    Ok(())
}
