//! `shaketable params`: write the defaults, or check and normalise a parameter file.

use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Print the TREES Lab defaults (spec section 6) as TOML.
    #[arg(long, conflicts_with = "check")]
    defaults: bool,
    /// Validate a parameter file and print it complete (every key, defaults filled in).
    #[arg(long, value_name = "FILE")]
    check: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let p = match (&args.check, args.defaults) {
        (Some(path), _) => shaketable::Params::from_file(path)?,
        (None, true) => shaketable::Params::trees_lab(),
        (None, false) => anyhow::bail!("say --defaults or --check FILE"),
    };
    print!("{}", p.to_toml_string());
    Ok(())
}
