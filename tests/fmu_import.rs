//! A second, independent client: the built FMU (scripts/build_fmu.sh) imported with the
//! `fmi` crate (rust-fmi, which loads the shared library with libloading), stepped with
//! get/set of reals, against the library simulator.

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common};
use fmi::traits::FmiImport;
use shaketable::solver::DEFAULT_MAX_SUBSTEP_S;
use shaketable::{Inputs, Model, Params, Reference, SensorNoise, Simulator};
use std::process::Command;

fn build_fmu(dir: &std::path::Path) -> std::path::PathBuf {
    let out = dir.join("ShakeTable.fmu");
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/build_fmu.sh");
    let o = Command::new("bash")
        .arg(script)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("run build_fmu.sh");
    assert!(
        o.status.success(),
        "build_fmu.sh: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

#[test]
fn rust_fmi_crate_runs_the_fmu() {
    let tmp = tempfile::tempdir().unwrap();
    let path = build_fmu(tmp.path());
    let import: Fmi2Import = fmi::import::from_path(&path).expect("import the FMU");
    assert_eq!(import.model_description().fmi_version, "2.0");
    let mut cs = import
        .instantiate_cs("rust-fmi", false, true)
        .expect("instantiate");
    cs.setup_experiment(None, 0.0, None).unwrap();
    cs.enter_initialization_mode().unwrap();
    cs.exit_initialization_mode().unwrap();
    let fs = 512.0;
    let w = 2.0 * std::f64::consts::PI * 2.0;
    let r = |k: usize| {
        let t = k as f64 / fs;
        [
            0.01 * (w * t).sin(),
            0.01 * w * (w * t).cos(),
            -0.01 * w * w * (w * t).sin(),
        ]
    };
    let mut sim = Simulator::new(Model::new(&Params::trees_lab()), 0.0, DEFAULT_MAX_SUBSTEP_S);
    let mut worst: f64 = 0.0;
    for k in 0..512 {
        let x = r(k);
        cs.set_real(&[0, 1, 2], &x).unwrap();
        cs.do_step(k as f64 / fs, 1.0 / fs, true).unwrap();
        let mut out = [0.0; 2];
        cs.get_real(&[10, 13], &mut out).unwrap();
        // the library with the input held over the step (no derivatives were set)
        let inp = Inputs {
            reference: Reference {
                displacement_m: x[0],
                velocity_m_s: x[1],
                acceleration_m_s2: x[2],
            },
            external_force_n: 0.0,
        };
        sim.advance(1.0 / fs, &inp, &inp, &SensorNoise::default());
        sim.time_s = (k + 1) as f64 / fs;
        let o = sim.outputs(&inp, &SensorNoise::default());
        worst = worst
            .max((out[0] - o.displacement_m).abs() / 0.01)
            .max((out[1] - o.actuator_force_n).abs() / 1e5);
    }
    assert!(worst < 1e-12, "difference {worst:e}");
    // the table followed the 10 mm, 2 Hz sine
    let mut x = [0.0];
    cs.get_real(&[10], &mut x).unwrap();
    assert!(x[0].abs() < 0.012);
}
