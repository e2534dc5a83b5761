//! `shaketable bench`: real-time factors of the simulator and the campaign synthesis.

#[derive(clap::Args)]
pub struct Args {
    /// Length of the random test simulated, s.
    #[arg(long, default_value_t = 90.0)]
    seconds: f64,
    /// Repetitions per workload (the best is kept).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    use crate::limits::{within, MAX_BENCH_REPEATS, MAX_BENCH_SECONDS};
    within(
        "--seconds",
        args.seconds,
        2.0,
        MAX_BENCH_SECONDS,
        "MAX_BENCH_SECONDS",
    )?;
    within(
        "--repeats",
        args.repeats,
        1,
        MAX_BENCH_REPEATS,
        "MAX_BENCH_REPEATS",
    )?;
    println!(
        "{:<52} {:>11} {:>9} {:>13}",
        "workload", "simulated s", "wall s", "x real time"
    );
    for row in shaketable::benchmark::run(args.seconds, args.repeats) {
        println!(
            "{:<52} {:>11.1} {:>9.3} {:>13.0}",
            row.workload,
            row.simulated_s,
            row.wall_s,
            row.realtime_factor()
        );
    }
    println!("(simulation rows: one core; sub-step 1/3072 s unless marked)");
    Ok(())
}
