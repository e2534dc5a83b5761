//! Dev tool: a synthetic campaign whose table also feels a force no catalogue row of
//! `model.md` section 7 describes (issue 17's open world), to check by hand that
//! `diagnose` says `explained: false` and locates the rest rather than naming a catalogue
//! effect. The laws and how they are put on the table: `tests/common/unknown_physics.rs`.
//!
//! ```text
//! cargo run --release --example unknown_physics -- LAW SEED OUT_DIR [RANDOM_DURATION_S [SCALE]]
//! ```
//! LAW: `none`, `quadratic_damping`, `cubic_spring` or `yielding_specimen`; SCALE
//! multiplies its strength (default 1).

#[path = "../tests/common/unknown_physics.rs"]
mod unknown_physics;

use shaketable::campaign::synth::SynthOptions;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [law, seed, out, ..] = &args[..] else {
        panic!("usage: unknown_physics LAW SEED OUT_DIR [RANDOM_DURATION_S [SCALE]]");
    };
    let opts = SynthOptions {
        seed: seed.parse().expect("seed"),
        random_duration_s: args.get(3).map_or(30.0, |s| s.parse().expect("duration")),
        ..SynthOptions::default()
    };
    let scale = args.get(4).map_or(1.0, |s| s.parse().expect("scale"));
    let dir = std::path::Path::new(out);
    unknown_physics::synthesise_with_body(law, scale, &opts, dir);
    eprintln!("wrote {} ({law} x {scale}, seed {seed})", dir.display());
}
