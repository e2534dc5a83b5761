//! `shaketable identify DIR`: the paper's section-4 identification of a campaign; JSON of
//! the estimates, an identified parameter file, a report with the figures, and a printed
//! table (against the truth when the campaign is synthetic and holds truth.toml).

use shaketable::campaign::format::read_campaign;
use shaketable::identify::identify;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Campaign directory (campaign.toml and one CSV per test).
    campaign: PathBuf,
    /// Write the estimates as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the identified parameter file (TOML) here.
    #[arg(long)]
    params_out: Option<PathBuf>,
    /// Write the report (index.html, README.md, figures) into this directory.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Replace existing --json/--params-out files, and write the report into a folder that
    /// is not a report of this command (never over an input, never through a symlink).
    #[arg(long)]
    force: bool,
    /// Parameter file with the true values to compare against (default: the campaign's
    /// truth.toml when it exists, as written by `campaign synth`).
    #[arg(long)]
    truth: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let campaign = read_campaign(&args.campaign)?;
    crate::campaign::warn_near_misses(&campaign);
    let mut inputs = crate::outputs::campaign_inputs(&campaign);
    let truth_path = args.truth.clone().or_else(|| {
        Some(args.campaign.join(shaketable::campaign::synth::TRUTH_FILE)).filter(|p| p.exists())
    });
    if let Some(p) = &truth_path {
        inputs.add(p);
    }
    let outputs = crate::outputs::Outputs::check(
        "identify",
        args.json.as_deref(),
        args.params_out.as_deref(),
        args.report.as_deref(),
        args.force,
        inputs,
    )?;
    let bar = crate::spinner(format!("identifying {}", args.campaign.display()));
    let id = identify(&campaign);
    bar.finish_and_clear();
    let truth = match &truth_path {
        Some(p) => Some(shaketable::Params::from_file(p)?),
        None => None,
    };
    let rows = shaketable::report::identify::summary_rows(&id, truth.as_ref());
    println!(
        "identification of {} ({:.2} s)",
        args.campaign.display(),
        t0.elapsed().as_secs_f64()
    );
    print!("{}", shaketable::report::read::text(&id.read));
    print!(
        "{}",
        shaketable::report::identify::text_table(&rows, truth.is_some())
    );
    print!(
        "{}",
        shaketable::report::read::screening_text(&id.screening)
    );
    // a model identified from motion sensors at odds bends to their error: said here and
    // in the JSON (`kinematics`, as the diagnosis's)
    let kinematics = shaketable::diagnose::kinematics::check(&campaign);
    if let Some(k) = &kinematics {
        println!("{}", k.text());
    }
    // a resonance in the mass band: the rigid model's mass is a compromise, say so
    for w in id.warnings() {
        println!("warning: {w}");
    }
    for m in &id.missing {
        println!("not identified: {m}");
    }
    for (k, why) in id.defaults() {
        println!("default kept in the parameter file: {k} ({why})");
    }
    if let Some(cl) = &id.closed_loop {
        print!("{}", shaketable::report::closed_loop::text(cl));
    }
    let mut json = id.to_json();
    json["kinematics"] = serde_json::to_value(&kinematics)?;
    outputs.write(
        &(serde_json::to_string_pretty(&json)? + "\n"),
        &id.params.to_toml_string(),
        |dir| {
            Ok(shaketable::report::identify::write(
                dir,
                &id,
                &rows,
                truth.is_some(),
            )?)
        },
    )?;
    Ok(())
}
