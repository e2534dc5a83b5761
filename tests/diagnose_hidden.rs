//! Diagnosis finds a hidden effect (issue 6): campaigns synthesised with one catalogue
//! effect whose parameters are drawn from a seeded generator over plausible ranges,
//! redrawn when the effect is too small to see (no channel of any test changes by more
//! than 5 times its noise RMS in noise-free runs), then `shaketable diagnose` run on the
//! files as a user would. Random records are 30 s to keep CI short.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shaketable::campaign::synth::{synthesise, NoiseLevels, SynthOptions};
use shaketable::Params;
use std::process::Command;

const RANDOM_S: f64 = 30.0;

/// The largest flow the sine program demands: A times the peak reference velocity.
fn largest_sine_flow(p: &Params) -> f64 {
    shaketable::campaign::synth::paper_program(RANDOM_S)
        .iter()
        .filter(|t| t.kind == shaketable::campaign::TestKind::Sine)
        .map(|t| 2.0 * std::f64::consts::PI * t.frequency_hz.unwrap() * t.amplitude_m.unwrap())
        .fold(0.0, f64::max)
        * p.actuator.piston_area_m2
}

/// A draw of `effect`'s parameters over the ranges, as `--effect` text, with its
/// main parameter's value; its size scaled by `strength` (specimen and foundation masses,
/// the deadband, the static friction excess; the flow limit raised towards the demand).
fn draw(effect: &str, rng: &mut ChaCha8Rng, p: &Params, strength: f64) -> (String, f64) {
    let u = |rng: &mut ChaCha8Rng, a: f64, b: f64| a + (b - a) * rng.gen::<f64>();
    match effect {
        "specimen" => {
            let (m, f, z) = (
                u(rng, 3e3, 40e3) * strength,
                u(rng, 2.0, 15.0),
                u(rng, 0.01, 0.08),
            );
            (
                format!("specimen:mass_kg={m},frequency_hz={f},damping_ratio={z}"),
                f,
            )
        }
        "foundation" => {
            let (m, f, z) = (
                u(rng, 1e5, 2e6) * strength,
                u(rng, 6.0, 40.0),
                u(rng, 0.01, 0.10),
            );
            (
                format!("foundation:mass_kg={m},frequency_hz={f},damping_ratio={z}"),
                f,
            )
        }
        "flow_saturation" => {
            let q = u(rng, 0.40, 0.85).powf(strength) * largest_sine_flow(p);
            (format!("flow_saturation:max_flow_m3_s={q}"), q)
        }
        "stick_slip" => {
            let (r, v) = (1.0 + u(rng, 0.5, 2.5) * strength, u(rng, 0.001, 0.010));
            (
                format!("stick_slip:static_ratio={r},stribeck_velocity_m_s={v}"),
                r,
            )
        }
        "valve_deadband" => {
            let d = u(rng, 0.005, 0.05) * strength;
            (format!("valve_deadband:deadband={d}"), d)
        }
        // ratios either side of symmetry, by a factor of 1.2 to 2 (times `strength` in log)
        "friction_asymmetry" | "flow_asymmetry" => {
            let sign = if rng.gen::<bool>() { 1.0 } else { -1.0 };
            let r = (sign * u(rng, 1.2f64.ln(), 2f64.ln()) * strength).exp();
            (format!("{effect}:ratio={r}"), r)
        }
        "free_play" => {
            let g = u(rng, 3e-4, 2e-3) * strength;
            (format!("free_play:gap_m={g}"), g)
        }
        _ => unreachable!(),
    }
}

/// Noise-free runs with and without the effect: does any channel of any test change by
/// more than 5 times its (default) noise RMS?
fn visible(base: &Params, with: &Params) -> bool {
    let opts = SynthOptions {
        noise: NoiseLevels::none(),
        random_duration_s: RANDOM_S,
        ..SynthOptions::default()
    };
    let a = synthesise(base, &opts, None);
    let b = synthesise(with, &opts, None);
    let n = NoiseLevels::default();
    let rms = |x: &Option<Vec<f64>>, y: &Option<Vec<f64>>| {
        let (x, y) = (x.as_deref().unwrap(), y.as_deref().unwrap());
        (x.iter().zip(y).map(|(p, q)| (p - q).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
    };
    a.records.iter().zip(&b.records).any(|(x, y)| {
        rms(&x.displacement_m, &y.displacement_m) > 5.0 * n.displacement_m
            || rms(&x.acceleration_m_s2, &y.acceleration_m_s2) > 5.0 * n.acceleration_m_s2
            || rms(&x.force_n, &y.force_n) > 5.0 * n.force_n
    })
}

struct Outcome {
    cause: String,
    /// Every cause named, in order of acceptance.
    causes: Vec<String>,
    parameters: serde_json::Value,
    gain: f64,
}

fn run_case(base: &Params, effect: Option<&str>, seed: u64) -> (Outcome, Option<f64>, String) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (spec, main) = match effect {
        None => (None, None),
        Some(e) => {
            let (s, v) = visible_draw(e, &mut rng, base, 1.0);
            (Some(s), Some(v))
        }
    };
    let (out, _) = diagnose_synthesised(base, spec.as_slice(), seed);
    (out, main, spec.unwrap_or_else(|| "none".into()))
}

/// A draw of `effect` (scaled by `strength` where the effect has a size: masses, the
/// deadband) redrawn until it is visible on `base`.
fn visible_draw(effect: &str, rng: &mut ChaCha8Rng, base: &Params, strength: f64) -> (String, f64) {
    loop {
        let (s, v) = draw(effect, rng, base, strength);
        let mut with = *base;
        with.apply_effect_spec(&s).unwrap();
        if visible(base, &with) {
            return (s, v);
        }
    }
}

/// Synthesise a campaign of `base` with the effects `specs` (seeded), diagnose it as a
/// user would; the outcome and the whole JSON.
fn diagnose_synthesised(
    base: &Params,
    specs: &[String],
    seed: u64,
) -> (Outcome, serde_json::Value) {
    let effect = specs
        .iter()
        .map(|s| s.split(':').next().unwrap())
        .collect::<Vec<_>>()
        .join("+");
    let effect = if effect.is_empty() {
        "none".to_string()
    } else {
        effect
    };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("campaign");
    let params = tmp.path().join("truth_base.toml");
    std::fs::write(&params, base.to_toml_string()).unwrap();
    let mut args: Vec<String> = [
        "campaign",
        "synth",
        "--quiet",
        "--random-duration",
        "30",
        "--seed",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    args.push(seed.to_string());
    args.push("--params".into());
    args.push(params.to_str().unwrap().into());
    for s in specs {
        args.push("--effect".into());
        args.push(s.clone());
    }
    args.push(dir.to_str().unwrap().into());
    let bin = env!("CARGO_BIN_EXE_shaketable");
    let o = Command::new(bin).args(&args).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json = tmp.path().join("diagnosis.json");
    let mut diagnose = Command::new(bin);
    diagnose.args([
        "diagnose",
        "--quiet",
        dir.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    if std::env::var_os("SHAKETABLE_TRACE").is_some() {
        // the diagnosis' trace shows with --nocapture while developing
        diagnose.stderr(std::process::Stdio::inherit());
    }
    let o = diagnose.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    dump(&json, &effect, seed);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let out = Outcome {
        cause: v["cause"].as_str().unwrap().to_string(),
        causes: v["causes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["effect"].as_str().unwrap().to_string())
            .collect(),
        parameters: v["parameters"].clone(),
        gain: v["gain"].as_f64().unwrap(),
    };
    (out, v)
}

/// Keeps a copy of the diagnosis JSON as `<effect>-<seed>.json` in the folder named by
/// `SHAKETABLE_DIAGNOSIS_DUMP`, when set: `scripts/behaviour_check.sh` compares these
/// byte for byte before and after a change meant to leave behaviour unchanged.
fn dump(json: &std::path::Path, effect: &str, seed: u64) {
    if let Ok(dir) = std::env::var("SHAKETABLE_DIAGNOSIS_DUMP") {
        let dir = std::path::Path::new(&dir);
        std::fs::create_dir_all(dir).unwrap();
        std::fs::copy(json, dir.join(format!("{effect}-{seed}.json"))).unwrap();
    }
}

/// The committed seed, or every seed of `SHAKETABLE_HIDDEN_SEEDS` (comma-separated) when
/// set: vary the draws while developing, so the method is not tuned to the committed ones.
fn seeds(committed: u64) -> Vec<u64> {
    match std::env::var("SHAKETABLE_HIDDEN_SEEDS") {
        Ok(v) => v.split(',').filter_map(|s| s.trim().parse().ok()).collect(),
        Err(_) => vec![committed],
    }
}

fn check(base: &Params, effect: &str, key: &str, tol: f64, seed: u64) {
    for seed in seeds(seed) {
        check_one(base, effect, key, tol, seed);
    }
}

fn check_one(base: &Params, effect: &str, key: &str, tol: f64, seed: u64) {
    let (o, truth, spec) = run_case(base, Some(effect), seed);
    let got = o.parameters[key].as_f64().unwrap_or(f64::NAN);
    let truth = truth.unwrap();
    eprintln!(
        "{spec} (seed {seed}): cause {} {key} {got} (truth {truth}), gain {:.2}",
        o.cause, o.gain
    );
    assert_eq!(o.cause, effect, "{spec} (seed {seed})");
    // exactly the effect present: no second cause
    assert_eq!(o.causes, [effect], "{spec} (seed {seed})");
    assert!(
        (got / truth - 1.0).abs() < tol,
        "{spec}: {key} {got} vs {truth}"
    );
    assert!(o.gain >= 1.5, "{spec}: gain {}", o.gain);
}

/// One seed: the specimen is also drawn with two and three modes (104, 111), on the
/// first-order valve (601) and beside stick-slip and a deadband (801, 803); seed 102 left
/// to keep CI under an hour (`SHAKETABLE_HIDDEN_SEEDS=102` runs it).
#[test]
fn finds_a_specimen() {
    check(&Params::trees_lab(), "specimen", "frequency_hz", 0.05, 101);
}

/// A specimen of several modes (spec section 7, second part), a building model's: each
/// further mode at 2.5 to 4 times the previous one's frequency with 20 to 60 % of its
/// mass, below 40 Hz (where the random tests' apparent mass is read), redrawn until each
/// mode is visible on the specimen without it. One cause, `specimen`, with every mode in
/// `modes`, each frequency within 5 %.
fn check_modes(n_modes: usize, committed: u64) {
    for seed in seeds(committed) {
        let base = Params::trees_lab();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let u = |rng: &mut ChaCha8Rng, a: f64, b: f64| a + (b - a) * rng.gen::<f64>();
        let (spec, truth) = 'draw: loop {
            let (one, f1) = draw("specimen", &mut rng, &base, 1.0);
            let mut mass: f64 = one
                .split("mass_kg=")
                .nth(1)
                .unwrap()
                .split(',')
                .next()
                .unwrap()
                .parse()
                .unwrap();
            let (mut spec, mut truth) = (one, vec![f1]);
            let mut fewer = base;
            fewer.apply_effect_spec(&spec).unwrap();
            if !visible(&base, &fewer) {
                continue;
            }
            for k in 2..=n_modes {
                mass *= u(&mut rng, 0.2, 0.6);
                let f = u(&mut rng, 2.5, 4.0) * truth[k - 2];
                let z = u(&mut rng, 0.01, 0.08);
                if f >= 40.0 {
                    continue 'draw;
                }
                spec = format!(
                    "{spec},mode{k}.mass_kg={mass},mode{k}.frequency_hz={f},mode{k}.damping_ratio={z}"
                );
                let mut more = base;
                more.apply_effect_spec(&spec).unwrap();
                if !visible(&fewer, &more) {
                    continue 'draw;
                }
                truth.push(f);
                fewer = more;
            }
            break (spec, truth);
        };
        let (o, v) = diagnose_synthesised(&base, std::slice::from_ref(&spec), seed);
        let modes = &o.parameters["modes"];
        eprintln!(
            "{spec} (seed {seed}): causes {:?}, modes {modes}, gain {:.2}",
            o.causes, o.gain
        );
        assert_eq!(
            o.causes,
            ["specimen"],
            "{spec} (seed {seed}): {}",
            v["causes"]
        );
        let fitted: Vec<f64> = modes
            .as_array()
            .unwrap_or_else(|| panic!("{spec}: one mode fitted: {}", o.parameters))
            .iter()
            .map(|m| m["frequency_hz"].as_f64().unwrap())
            .collect();
        assert_eq!(fitted.len(), n_modes, "{spec}: modes {modes}");
        for (got, want) in fitted.iter().zip(truth) {
            assert!(
                (got / want - 1.0).abs() < 0.05,
                "{spec}: mode at {got} Hz vs {want}"
            );
        }
    }
}

#[test]
fn finds_a_specimen_with_two_modes() {
    check_modes(2, 104);
}

#[test]
fn finds_a_specimen_with_three_modes() {
    check_modes(3, 111);
}

/// Stiff foundations (seed 201: 590 t at 37.7 Hz) move the table by less than the LVDT
/// noise; their mode shows in the 32-64 Hz octave of R1's force and acceleration, which
/// the band-resolved score sees. The second draw is on the nonlinear actuator
/// ([`finds_a_foundation_on_the_nonlinear_actuator`]).
#[test]
fn finds_a_foundation() {
    check(
        &Params::trees_lab(),
        "foundation",
        "frequency_hz",
        0.10,
        201,
    );
}

/// A heavy, lightly damped foundation at low frequency (seed 202: 1970 t, 10.7 Hz, 1.5 %):
/// a sharp mode a few percent off misfits more than none until the baseline has unbent,
/// so the start read off the LVDT/accelerometer discrepancy is fitted whatever its
/// screening.
#[test]
fn finds_a_soft_lightly_damped_foundation() {
    check(
        &Params::trees_lab(),
        "foundation",
        "frequency_hz",
        0.10,
        202,
    );
}

/// Stick-slip chatter grows out of the in-loop noise: fitted from the friction-velocity
/// curve of the slow tests, polished on the predictive score (noise-driven runs). Seed
/// 303 (r_s 1.75, v_s 7.1 mm/s: weak, intermittent chatter) was named `none`, then found
/// 36 % off by the grid the curve replaced.
#[test]
fn finds_stick_slip() {
    for seed in [301, 302, 303] {
        check(
            &Params::trees_lab(),
            "stick_slip",
            "static_ratio",
            0.25,
            seed,
        );
    }
}

#[test]
fn finds_flow_saturation() {
    check(
        &Params::trees_lab(),
        "flow_saturation",
        "max_flow_m3_s",
        0.10,
        401,
    );
    check(
        &Params::trees_lab(),
        "flow_saturation",
        "max_flow_m3_s",
        0.10,
        402,
    );
}

#[test]
fn finds_a_valve_deadband() {
    check(
        &Params::trees_lab(),
        "valve_deadband",
        "deadband",
        0.25,
        501,
    );
    check(
        &Params::trees_lab(),
        "valve_deadband",
        "deadband",
        0.25,
        502,
    );
}

/// The second part of the catalogue (issue 17 part 1): ratios within 15 %, the gap
/// within 30 %.
#[test]
fn finds_friction_asymmetry() {
    check(
        &Params::trees_lab(),
        "friction_asymmetry",
        "ratio",
        0.15,
        701,
    );
}

#[test]
fn finds_flow_asymmetry() {
    check(&Params::trees_lab(), "flow_asymmetry", "ratio", 0.15, 702);
}

/// The gap is read off the slow tests' reversals and polished on the predictive score of
/// the wide-band valve test and the fastest sine (its impacts are chaotic in detail).
/// Other seeds (stop 54, `SHAKETABLE_HIDDEN_SEEDS`): 12 (0.30 mm, +26 %), 13 (0.87 mm,
/// -1.5 %), 14 (1.47 mm, -2.4 %), 15 (1.65 mm, -3.8 %), 16 (0.54 mm, +2.3 %; not found
/// before stop 54), 17 (1.50 mm, +12 %), 18 (0.52 mm, +3 %), 19 (1.09 mm, -0.7 %) name
/// the play alone.
#[test]
fn finds_free_play() {
    check(&Params::trees_lab(), "free_play", "gap_m", 0.30, 703);
}

/// First-order valve and nonlinear actuator as the truth's baseline.
#[test]
fn finds_effects_on_other_baselines() {
    let mut first = Params::trees_lab();
    first.servovalve.model = shaketable::params::ServovalveModel::FirstOrder;
    check(&first, "specimen", "frequency_hz", 0.05, 601);
    let mut nonlinear = Params::trees_lab();
    nonlinear.actuator.model = shaketable::params::ActuatorModel::Nonlinear;
    check(&nonlinear, "valve_deadband", "deadband", 0.25, 603);
}

/// A table whose oil column lies far from the TREES Lab's 14 Hz: 15 t on the TREES Lab
/// actuator, its column at 23.5 Hz (seed 604: a 37-t specimen at 6.14 Hz). Until stop 51
/// section 4 fitted such a column from the paper's 14-Hz start alone and stopped near
/// 15 Hz; the output-error refinement recovered from that on this table (a 5-t specimen
/// at 8 Hz, seed 474, was found either way), on a 6-t one it did not.
#[test]
fn finds_a_specimen_on_a_lighter_table() {
    check(
        &fifteen_tonne_table(),
        "specimen",
        "frequency_hz",
        0.05,
        604,
    );
}

/// A specimen twice as heavy as its table, its mode low in the rigid-mass band (seed 605:
/// 33 t at 4.43 Hz on the 15-t table). Until stop 53 `identify`'s rigid mass over 2-20 Hz
/// came out 4.4 t, the refined baseline diverged and no cause was named; now the apparent
/// mass's fit of a table carrying one mode gives the mass that moves below the mode
/// (48 t) and the specimen's start. Until stop 52 a specimen's fit could not move the table
/// mass below half the identified mass, and seed 606 (33.5 t at 8.52 Hz) named a
/// foundation. Seeds 606-611 (4-35 t at 7-14 Hz) pass too.
#[test]
fn finds_a_specimen_twice_as_heavy_as_its_table() {
    check(
        &fifteen_tonne_table(),
        "specimen",
        "frequency_hz",
        0.05,
        605,
    );
}

/// The TREES Lab table at 15 t on its own actuator: its oil column at 23.5 Hz.
fn fifteen_tonne_table() -> Params {
    let mut light = Params::trees_lab();
    light.table.mass_kg = 15_000.0;
    light
}

/// The foundation on the nonlinear-actuator baseline (see [`finds_a_foundation`]).
#[test]
fn finds_a_foundation_on_the_nonlinear_actuator() {
    let mut nonlinear = Params::trees_lab();
    nonlinear.actuator.model = shaketable::params::ActuatorModel::Nonlinear;
    check(&nonlinear, "foundation", "frequency_hz", 0.10, 602);
}

#[test]
fn names_no_effect_when_there_is_none() {
    for seed in [701, 702] {
        let (o, _, _) = run_case(&Params::trees_lab(), None, seed);
        eprintln!("none (seed {seed}): cause {}, gain {:.2}", o.cause, o.gain);
        assert_eq!(o.cause, "none", "seed {seed}");
        assert!(o.causes.is_empty(), "seed {seed}: {:?}", o.causes);
    }
}

/// Issue 17 part 2: two effects at once, each drawn and redrawn until visible alone; the
/// diagnosis must name exactly both (in `causes`, any order) and fit each one's main
/// parameter within the single-effect tolerances.
fn check_pair(first: (&str, &str, f64), second: (&str, &str, f64), weak: f64, seed: u64) {
    for seed in seeds(seed) {
        let base = Params::trees_lab();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let a = visible_draw(first.0, &mut rng, &base, 1.0);
        let b = visible_draw(second.0, &mut rng, &base, weak);
        let specs = [a.0.clone(), b.0.clone()];
        let (_, v) = diagnose_synthesised(&base, &specs, seed);
        let causes = v["causes"].as_array().unwrap();
        let named: Vec<&str> = causes
            .iter()
            .map(|c| c["effect"].as_str().unwrap())
            .collect();
        eprintln!(
            "{specs:?} (seed {seed}): causes {named:?}, gain {}",
            v["gain"]
        );
        let mut want = vec![first.0, second.0];
        let mut got = named.clone();
        want.sort_unstable();
        got.sort_unstable();
        assert_eq!(got, want, "{specs:?} (seed {seed}): {}", v["causes"]);
        for ((effect, key, tol), truth) in [(first, a.1), (second, b.1)] {
            let c = causes.iter().find(|c| c["effect"] == effect).unwrap();
            let fitted = c["parameters"][key].as_f64().unwrap();
            assert!(
                (fitted / truth - 1.0).abs() < tol,
                "{specs:?} (seed {seed}): {effect}.{key} {fitted} vs {truth}"
            );
        }
    }
}

#[test]
fn finds_a_specimen_and_stick_slip() {
    check_pair(
        ("specimen", "frequency_hz", 0.05),
        ("stick_slip", "static_ratio", 0.25),
        1.0,
        801,
    );
}

/// A soft 1148-t foundation at 12.7 Hz under a table whose flow saturates on the fast
/// sines (seed 802): the first search names the flow saturation; the second found the
/// foundation only once its fit kept the best start at each grid frequency
/// (`keep_each_frequency` in `src/diagnose/starts.rs`), not the best two overall.
#[test]
fn finds_a_foundation_and_flow_saturation() {
    check_pair(
        ("foundation", "frequency_hz", 0.10),
        ("flow_saturation", "max_flow_m3_s", 0.10),
        1.0,
        802,
    );
}

/// The second effect weak: a deadband a fifth of the single-effect draws' size, redrawn
/// until just visible (5 noise RMS in some channel of some test).
#[test]
fn finds_a_specimen_and_a_weak_valve_deadband() {
    check_pair(
        ("specimen", "frequency_hz", 0.05),
        ("valve_deadband", "deadband", 0.25),
        0.2,
        803,
    );
}
