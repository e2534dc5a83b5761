//! `shaketable fmu`: the files of the FMU generated from the variable table (used by
//! scripts/build_fmu.sh): modelDescription.xml and documentation/index.html, with a
//! parameter file's values as start values.

use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(clap::Subcommand)]
enum What {
    /// Print modelDescription.xml.
    Description {
        /// Parameter file whose values become the start values (defaults when omitted).
        #[arg(long)]
        params: Option<PathBuf>,
        /// `generationDateAndTime` (ISO 8601 UTC, e.g. 2026-11-24T18:00:00Z); omitted when
        /// not given, so the committed copy is reproducible.
        #[arg(long, value_name = "DATE")]
        generated_at: Option<String>,
        /// FMI version of the description: 2 (Co-Simulation and Model Exchange,
        /// ShakeTable.fmu) or 3 (Co-Simulation, ShakeTable3.fmu).
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u8).range(2..=3))]
        fmi_version: u8,
    },
    /// Write model.png, the FMU's icon.
    Icon {
        #[arg(long, value_name = "PNG")]
        out: PathBuf,
        /// Replace --out if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Print documentation/index.html (the variable table).
    Documentation {
        #[arg(long)]
        params: Option<PathBuf>,
    },
    /// Print a parameter file as the FMU's start values (JSON: variable name -> value),
    /// for an FMI master (e.g. scripts/play_drive.py) to set before initialisation.
    StartValues {
        #[arg(long)]
        params: Option<PathBuf>,
    },
}

pub fn run(args: Args) -> anyhow::Result<()> {
    use shaketable::fmi::model_description::{
        documentation_html, model_description_xml, model_description_xml_at,
    };
    match args.what {
        What::Description {
            params,
            generated_at,
            fmi_version,
        } => {
            let p = crate::load_params(params.as_deref())?;
            if let Some(date) = &generated_at {
                check_date(date)?;
            }
            let xml = match (fmi_version, generated_at.as_deref()) {
                (3, date) => {
                    shaketable::fmi::fmi3::model_description::model_description_xml(&p, date)
                }
                (_, Some(date)) => model_description_xml_at(&p, date),
                (_, None) => model_description_xml(&p),
            };
            print!("{xml}");
        }
        What::Icon { out, force } => {
            use shaketable::output::{check_file, write_via_temp, Inputs};
            check_file(&out, force, &Inputs::new())?;
            write_via_temp(&out, shaketable::fmi::icon::draw_icon, |e| e.to_string())
                .map_err(|e| anyhow::anyhow!("{}: {e}", out.display()))?;
        }
        What::Documentation { params } => print!(
            "{}",
            documentation_html(&crate::load_params(params.as_deref())?)
        ),
        What::StartValues { params } => {
            use shaketable::fmi::variables::{Kind, Role, VARIABLES};
            let p = crate::load_params(params.as_deref())?;
            let mut values = serde_json::Map::new();
            for v in VARIABLES {
                if let Role::Parameter(get, _) = v.role {
                    let x = get(&p);
                    let value = match v.kind {
                        Kind::Real => serde_json::json!(x),
                        Kind::Integer => serde_json::json!(x as i64),
                        Kind::Boolean => serde_json::json!(x != 0.0),
                    };
                    values.insert(v.name.to_string(), value);
                }
            }
            println!("{}", serde_json::to_string_pretty(&values)?);
        }
    }
    Ok(())
}

/// `generationDateAndTime` is an xs:dateTime: refuse anything else before it reaches the XML.
fn check_date(date: &str) -> anyhow::Result<()> {
    let b = date.as_bytes();
    let digits =
        |r: std::ops::Range<usize>| r.clone().all(|i| b.get(i).is_some_and(u8::is_ascii_digit));
    let shape = b.len() == 20
        && digits(0..4)
        && b[4] == b'-'
        && digits(5..7)
        && b[7] == b'-'
        && digits(8..10)
        && b[10] == b'T'
        && digits(11..13)
        && b[13] == b':'
        && digits(14..16)
        && b[16] == b':'
        && digits(17..19)
        && b[19] == b'Z';
    anyhow::ensure!(
        shape,
        "--generated-at `{date}` is not a UTC date and time like 2026-11-24T18:00:00Z"
    );
    Ok(())
}
