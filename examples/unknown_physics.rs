//! Dev tool: a synthetic campaign whose table also feels a force no catalogue row of
//! `model.md` section 7 describes (issue 17's open world), to check by hand that
//! `diagnose` says `explained: false` and locates the rest rather than naming a catalogue
//! effect. The laws and how they are put on the table: `tests/common/unknown_physics.rs`.
//!
//! ```text
//! cargo run --release --example unknown_physics -- LAW SEED OUT_DIR [RANDOM_DURATION_S [SCALE [EFFECT...]]]
//! ```
//! LAW: `none`, `quadratic_damping`, `cubic_spring` or `yielding_specimen`; SCALE
//! multiplies its strength (default 1); each EFFECT is a catalogue effect on the table
//! as `campaign synth --effect` writes it (`specimen:mass_kg=15000,frequency_hz=5`).

#[path = "../tests/common/unknown_physics.rs"]
mod unknown_physics;

use shaketable::campaign::synth::SynthOptions;
use shaketable::Params;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [law, seed, out, ..] = &args[..] else {
        panic!("usage: unknown_physics LAW SEED OUT_DIR [RANDOM_DURATION_S [SCALE [EFFECT...]]]");
    };
    let opts = SynthOptions {
        seed: seed.parse().expect("seed"),
        random_duration_s: args.get(3).map_or(30.0, |s| s.parse().expect("duration")),
        ..SynthOptions::default()
    };
    let scale = args.get(4).map_or(1.0, |s| s.parse().expect("scale"));
    let mut table = Params::trees_lab();
    for effect in args.iter().skip(5) {
        table.apply_effect_spec(effect).expect("effect");
    }
    let dir = std::path::Path::new(out);
    unknown_physics::synthesise_with_body(&table, law, scale, &opts, dir);
    eprintln!("wrote {} ({law} x {scale}, seed {seed})", dir.display());
}
