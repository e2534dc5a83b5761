//! `shaketable simulate`: drive the model with the reference channels of a campaign-format
//! CSV (noise-free) and write every output channel as a campaign-format CSV.
//!
//! With `--campaign DIR --test NAME` the reference is that test's, read as the campaign
//! maps it (a laboratory's columns, units and rate; derivatives computed from the one
//! recorded reference channel).
//!
//! Controller gains: the parameter file's `[controller]`, with the per-test override of
//! the campaign the CSV belongs to applied (e.g. R1's `controller = { fv = 0.0 }`), as
//! the test was run with it. The campaign is `--campaign-dir`, or else the campaign.toml
//! next to the CSV when it lists that file; `--no-campaign` ignores both. The sample
//! rate is `--sample-rate`, else the campaign's, else inferred from the time column.

use shaketable::campaign::format::{
    read_campaign_info, read_campaign_test, read_reference, record_to_csv, ReferenceRecord,
};
use shaketable::campaign::{CampaignInfo, Record, TestSpec};
use shaketable::output::{self, Inputs};
use shaketable::solver::simulate_run_observed;
use shaketable::solver::DEFAULT_MAX_SUBSTEP_S;
use shaketable::Model;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// Parameter file (TOML); the TREES Lab defaults when omitted.
    #[arg(long, value_name = "FILE")]
    params: Option<PathBuf>,
    /// Switch on a catalogue effect, e.g. `foundation:mass_kg=2e5,frequency_hz=8` (repeatable).
    #[arg(long = "effect", value_name = "NAME:KEY=VALUE,...")]
    effects: Vec<String>,
    /// Campaign-format CSV with time_s and the ref_* channels (others are ignored).
    #[arg(
        long,
        value_name = "CSV",
        required_unless_present = "test",
        conflicts_with = "test"
    )]
    reference: Option<PathBuf>,
    /// A test of the campaign `--campaign DIR`, read with the campaign's mapping, sample
    /// rate and reference, simulated with its controller override.
    #[arg(long, value_name = "NAME", requires = "campaign_dir")]
    test: Option<String>,
    /// Output CSV (campaign format, every output channel).
    #[arg(long, value_name = "CSV")]
    out: PathBuf,
    /// Sample rate of the reference, Hz (checked against its time column).
    #[arg(long, value_name = "HZ")]
    sample_rate: Option<f64>,
    /// Campaign directory whose campaign.toml lists the reference (per-test controller
    /// overrides are applied). Default: the CSV's own directory, if it has a campaign.toml.
    #[arg(
        long,
        visible_alias = "campaign",
        value_name = "DIR",
        conflicts_with = "no_campaign"
    )]
    campaign_dir: Option<PathBuf>,
    /// Ignore any campaign.toml next to the reference.
    #[arg(long)]
    no_campaign: bool,
    /// Largest solver sub-step, s.
    #[arg(long, default_value_t = DEFAULT_MAX_SUBSTEP_S, value_name = "S")]
    max_substep: f64,
    /// Replace --out if it exists (never an input of this run, never through a symlink).
    #[arg(long)]
    force: bool,
}

/// The campaign test that records `reference`, if any.
fn find_test<'a>(info: &'a CampaignInfo, dir: &Path, reference: &Path) -> Option<&'a TestSpec> {
    let target = reference.canonicalize().ok()?;
    info.tests
        .iter()
        .find(|t| dir.join(&t.file).canonicalize().ok().as_ref() == Some(&target))
}

/// The numeric options that size run time, within their limits.
fn check_limits(a: &Args) -> anyhow::Result<()> {
    use crate::limits::{at_least, within, MAX_SAMPLE_RATE_HZ, MIN_SUBSTEP_S};
    if let Some(fs) = a.sample_rate {
        within(
            "--sample-rate",
            fs,
            f64::MIN_POSITIVE,
            MAX_SAMPLE_RATE_HZ,
            "Hz; MAX_SAMPLE_RATE_HZ",
        )?;
    }
    at_least(
        "--max-substep",
        a.max_substep,
        MIN_SUBSTEP_S,
        "s; MIN_SUBSTEP_S",
    )
}

pub fn run(a: Args) -> anyhow::Result<()> {
    let mut params = crate::load_params(a.params.as_deref())?;
    for e in &a.effects {
        params
            .apply_effect_spec(e)
            .map_err(|m| anyhow::anyhow!("--effect {e}: {m}"))?;
    }
    check_limits(&a)?;
    let mut inputs = Inputs::new();
    for p in a.params.iter() {
        inputs.add(p);
    }
    let (reference, source) = match (&a.test, &a.reference) {
        (Some(name), _) => (
            test_reference(&a, name, &mut params, &mut inputs)?,
            name.clone(),
        ),
        (None, Some(file)) => (
            file_reference(&a, file, &mut params, &mut inputs)?,
            file.display().to_string(),
        ),
        (None, None) => anyhow::bail!("give --reference CSV or --campaign DIR --test NAME"),
    };
    let fs = reference.sample_rate_hz;
    if let Some(w) = shaketable::linear::stability_warning(&params) {
        eprintln!("warning: {w}");
    }
    let model = Model::new(&params);
    let samples = reference.time_s.len();
    // a bar on a terminal only (indicatif hides it when stderr is not one)
    let bar = indicatif::ProgressBar::new(samples as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "simulating {bar:30} {pos}/{len} samples ({elapsed}, eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let run = simulate_run_observed(&model, &reference.inputs(), fs, a.max_substep, &|k| {
        bar.set_position(k as u64)
    });
    bar.finish_and_clear();
    if let Some(stop) = run.stop {
        anyhow::bail!("simulating {source}: {}", stop.reason);
    }
    let out = run.outputs;
    let col = |f: fn(&shaketable::Outputs) -> f64| out.iter().map(f).collect::<Vec<f64>>();
    let record = Record {
        time_s: reference.time_s.clone(),
        ref_displacement_m: reference.ref_displacement_m.clone(),
        ref_velocity_m_s: reference.ref_velocity_m_s.clone(),
        ref_acceleration_m_s2: reference.ref_acceleration_m_s2.clone(),
        valve_command: Some(col(|o| o.valve_command)),
        spool_position: Some(col(|o| o.spool_position)),
        displacement_m: Some(col(|o| o.displacement_m)),
        acceleration_m_s2: Some(col(|o| o.acceleration_m_s2)),
        force_n: Some(col(|o| o.actuator_force_n)),
        extra: vec![
            ("velocity_m_s".to_string(), col(|o| o.velocity_m_s)),
            ("pressure_a_pa".to_string(), col(|o| o.pressure_a_pa)),
            ("pressure_b_pa".to_string(), col(|o| o.pressure_b_pa)),
        ],
    };
    let bytes = record_to_csv(&record, &a.out.display().to_string())?;
    output::write_file(&a.out, &bytes, a.force, &inputs)?;
    eprintln!(
        "simulated {} samples ({} s at {fs} Hz), wrote {}",
        record.len(),
        record.len() as f64 / fs,
        a.out.display()
    );
    Ok(())
}

/// The reference of test `name` of `--campaign DIR` (its mapping, rate and derivatives),
/// with the test's controller override applied to the parameter file's gains.
fn test_reference(
    a: &Args,
    name: &str,
    params: &mut shaketable::Params,
    inputs: &mut Inputs,
) -> anyhow::Result<ReferenceRecord> {
    let dir = a.campaign_dir.as_deref().unwrap_or(Path::new("."));
    let (info, record) = read_campaign_test(dir, name)?;
    inputs.add(&dir.join("campaign.toml"));
    for t in &info.tests {
        inputs.add(&dir.join(&t.file));
    }
    output::check_file(&a.out, a.force, inputs)?;
    let Some(spec) = info.tests.iter().find(|t| t.name == name) else {
        anyhow::bail!("{}: no test `{name}`", dir.display());
    };
    apply_test_controller(params, &info, spec, dir);
    // the test's own rate, else the campaign's (campaign-format.md)
    let rate = info.sample_rate_for(spec);
    if let Some(fs) = a.sample_rate.filter(|fs| *fs != rate) {
        anyhow::bail!(
            "--sample-rate {fs} Hz disagrees with {}",
            rate_origin(spec, rate)
        );
    }
    Ok(ReferenceRecord {
        sample_rate_hz: rate,
        time_s: record.time_s,
        ref_displacement_m: record.ref_displacement_m,
        ref_velocity_m_s: record.ref_velocity_m_s,
        ref_acceleration_m_s2: record.ref_acceleration_m_s2,
    })
}

/// Test `spec`'s rate `rate` and where it comes from, for a message.
fn rate_origin(spec: &TestSpec, rate: f64) -> String {
    match spec.sample_rate_hz {
        Some(_) => format!("test `{}`'s own {rate} Hz", spec.name),
        None => format!("the campaign's {rate} Hz"),
    }
}

/// The reference of `--reference FILE`, with the controller override of the campaign
/// test that records it (if any); the output is checked before it is read.
fn file_reference(
    a: &Args,
    reference_file: &Path,
    params: &mut shaketable::Params,
    inputs: &mut Inputs,
) -> anyhow::Result<ReferenceRecord> {
    let campaign = campaign_of(a, reference_file)?;
    let mut fs = a.sample_rate;
    if let Some((dir, info)) = &campaign {
        match find_test(info, dir, reference_file) {
            Some(t) => {
                apply_test_controller(params, info, t, dir);
                fs = fs.or(Some(info.sample_rate_for(t)));
            }
            None if a.campaign_dir.is_some() => anyhow::bail!(
                "{}: no test of {} lists this file",
                reference_file.display(),
                dir.join("campaign.toml").display()
            ),
            None => {}
        }
    }
    // the output is checked before the simulation: never the reference, never a symlink
    inputs.add(reference_file);
    if let Some((dir, info)) = &campaign {
        inputs.add(&dir.join("campaign.toml"));
        for t in &info.tests {
            inputs.add(&dir.join(&t.file));
        }
    }
    output::check_file(&a.out, a.force, inputs)?;
    Ok(read_reference(reference_file, fs)?)
}

/// The parameter file's gains with `spec`'s override, as the test was run; says so, and
/// when the parameter file's gains differ from the campaign's.
fn apply_test_controller(
    params: &mut shaketable::Params,
    info: &CampaignInfo,
    spec: &TestSpec,
    dir: &Path,
) {
    let gains = spec.controller.apply(&params.controller);
    if spec.controller != Default::default() {
        eprintln!(
            "note: test `{}` of {}: controller override applied: {:?}",
            spec.name,
            dir.join("campaign.toml").display(),
            gains
        );
    }
    if info
        .controller
        .complete()
        .is_ok_and(|k| k != params.controller)
    {
        eprintln!(
            "note: the parameter file's [controller] differs from the campaign's; \
             simulating with the parameter file's gains (plus the test override)"
        );
    }
    params.controller = gains;
}

/// The campaign `--reference` belongs to: `--campaign DIR`, else the campaign.toml next
/// to the file (ignored with a note when unreadable), unless `--no-campaign`.
fn campaign_of(a: &Args, reference_file: &Path) -> anyhow::Result<Option<(PathBuf, CampaignInfo)>> {
    Ok(if a.no_campaign {
        None
    } else if let Some(dir) = &a.campaign_dir {
        let info = read_campaign_info(dir)?;
        Some((dir.clone(), info))
    } else {
        let dir = reference_file
            .parent()
            .map(|p| {
                if p.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    p
                }
            })
            .unwrap_or(Path::new("."))
            .to_path_buf();
        if dir.join("campaign.toml").exists() {
            match read_campaign_info(&dir) {
                Ok(info) => Some((dir, info)),
                Err(e) => {
                    eprintln!("note: ignoring the campaign next to the reference: {e}");
                    None
                }
            }
        } else {
            None
        }
    })
}
