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
    use shaketable::fmi::model_description::{documentation_html, model_description_xml};
    match args.what {
        What::Description { params } => print!(
            "{}",
            model_description_xml(&crate::load_params(params.as_deref())?)
        ),
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
