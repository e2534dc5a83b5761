//! The FMU's C ABI exercised in-process (the exported functions of the crate, called
//! through their FMI 2.0 signatures): equality with the library simulator, state
//! get/set/serialize, independent instances, reset, step-size independence, and property
//! tests of random call sequences and of out-of-envelope parameters, both from random
//! resource locations (no crash, no hang, an allowed status, a logged message per error).

use fmi_sys::fmi2::*;
use proptest::prelude::*;
use shaketable::fmi::export::*;
use shaketable::fmi::model_description::guid as description_guid;
use shaketable::solver::DEFAULT_MAX_SUBSTEP_S;
use shaketable::{Model, Params, SensorNoise, Simulator};
use std::ffi::CString;

mod common;
use common::fmu::*;

const INPUTS: [u32; 3] = [0, 1, 2];
const OUTPUTS: [u32; 8] = [10, 11, 12, 13, 14, 15, 16, 17];

/// Reference sample k of a 3 Hz, 5 mm sine at `fs`.
fn reference(k: usize, fs: f64) -> [f64; 3] {
    let w = 2.0 * std::f64::consts::PI * 3.0;
    let t = k as f64 / fs;
    [
        0.005 * (w * t).sin(),
        0.005 * w * (w * t).cos(),
        -0.005 * w * w * (w * t).sin(),
    ]
}

/// The 512 Hz reference linearly interpolated at `fs` (a multiple of 512 Hz): the same
/// continuous input whatever the communication step.
fn reference_at(k: usize, fs: f64) -> [f64; 3] {
    let m = (fs / 512.0).round() as usize;
    let (i, j) = (k / m, k % m);
    let (a, b) = (reference(i, 512.0), reference(i + 1, 512.0));
    let w = j as f64 / m as f64;
    [0, 1, 2].map(|n| a[n] + w * (b[n] - a[n]))
}

/// Drive the FMU with linearly interpolated inputs (values and slopes each step).
fn drive(f: &Fmu, from: usize, to: usize, fs: f64) -> Vec<Vec<f64>> {
    let h = 1.0 / fs;
    let mut out = Vec::new();
    for k in from..to {
        let (a, b) = (reference_at(k, fs), reference_at(k + 1, fs));
        assert_eq!(f.set(&INPUTS, &a), 0);
        let s: Vec<f64> = (0..3).map(|i| (b[i] - a[i]) / h).collect();
        assert_eq!(f.slopes(&INPUTS, &s), 0);
        assert_eq!(f.step(k as f64 * h, h), 0);
        assert_eq!(f.set(&INPUTS, &b), 0);
        out.push(f.get(&OUTPUTS));
    }
    out
}

/// The boundary adds nothing: the FMU equals the library's simulator within 1e-9.
#[test]
fn fmu_equals_the_library_simulator() {
    let fs = 512.0;
    let f = Fmu::new("equal");
    f.init();
    let got = drive(&f, 0, 1024, fs);
    let mut sim = Simulator::new(Model::new(&Params::trees_lab()), 0.0, DEFAULT_MAX_SUBSTEP_S);
    let inp = |k: usize| {
        let r = reference(k, fs);
        shaketable::fmi::variables::inputs_from(&[r[0], r[1], r[2], 0.0])
    };
    assert_eq!(got.len(), 1024, "one row per step");
    let mut worst: f64 = 0.0;
    for (k, row) in got.iter().enumerate().take(1024) {
        sim.advance(1.0 / fs, &inp(k), &inp(k + 1), &SensorNoise::default());
        sim.time_s = (k + 1) as f64 / fs;
        let o = sim.outputs(&inp(k + 1), &SensorNoise::default());
        let lib = [
            o.displacement_m,
            o.velocity_m_s,
            o.acceleration_m_s2,
            o.actuator_force_n,
            o.valve_command,
            o.spool_position,
            o.pressure_a_pa,
            o.pressure_b_pa,
        ];
        for i in 0..8 {
            worst = worst.max(
                (row[i] - lib[i]).abs()
                    / lib[i].abs().max(1e-12 * (1.0 + lib[i].abs())).max(1e-300),
            );
        }
    }
    assert!(worst <= 1e-9, "largest relative difference {worst:e}");
}

/// Results at 1/512 s and 1/1024 s communication steps agree within the solver's accuracy
/// (the same piecewise-linear input at both steps).
#[test]
fn communication_step_does_not_change_the_answer() {
    let a = Fmu::new("coarse");
    a.init();
    let b = Fmu::new("fine");
    b.init();
    let ra = drive(&a, 0, 1024, 512.0);
    let rb = drive(&b, 0, 2048, 1024.0);
    // compare the force at common times, relative to its RMS
    let fa: Vec<f64> = ra.iter().map(|o| o[3]).collect();
    let fb: Vec<f64> = rb.iter().skip(1).step_by(2).map(|o| o[3]).collect();
    let rms = (fa.iter().map(|x| x * x).sum::<f64>() / fa.len() as f64).sqrt();
    let diff = (fa
        .iter()
        .zip(&fb)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        / fa.len() as f64)
        .sqrt();
    assert!(
        diff / rms < 1e-6,
        "relative RMS difference {:e}",
        diff / rms
    );
}

#[test]
fn fmu_state_get_set_and_serialize_continue_bit_identically() {
    let fs = 512.0;
    let f = Fmu::new("state");
    f.init();
    drive(&f, 0, 300, fs);
    let mut s: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(unsafe { fmi2GetFMUstate(f.c, &mut s) }, 0);
    let mut size = 0usize;
    assert_eq!(unsafe { fmi2SerializedFMUstateSize(f.c, s, &mut size) }, 0);
    let mut bytes = vec![0 as fmi2Byte; size];
    assert_eq!(
        unsafe { fmi2SerializeFMUstate(f.c, s, bytes.as_mut_ptr(), size) },
        0
    );
    let first = drive(&f, 300, 600, fs);
    // back to the saved state
    assert_eq!(unsafe { fmi2SetFMUstate(f.c, s) }, 0);
    let again = drive(&f, 300, 600, fs);
    // through the serialized bytes, in a fresh instance
    let g = Fmu::new("state2");
    let mut s2: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(
        unsafe { fmi2DeSerializeFMUstate(g.c, bytes.as_ptr(), size, &mut s2) },
        0
    );
    assert_eq!(unsafe { fmi2SetFMUstate(g.c, s2) }, 0);
    let third = drive(&g, 300, 600, fs);
    let bits = |v: &Vec<Vec<f64>>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&first), bits(&again));
    assert_eq!(bits(&first), bits(&third));
    unsafe {
        assert_eq!(fmi2FreeFMUstate(f.c, &mut s), 0);
        assert_eq!(fmi2FreeFMUstate(g.c, &mut s2), 0);
    }
    assert!(s.is_null());
}

#[test]
fn instances_are_independent_and_reset_restarts() {
    let fs = 512.0;
    let alone = Fmu::new("alone");
    alone.init();
    let ra = drive(&alone, 0, 200, fs);
    let a = Fmu::new("a");
    let b = Fmu::new("b");
    assert_eq!(b.set(&[130], &[2.0 * 41258.0]), 0);
    a.init();
    b.init();
    // b gets a heavier table before it runs: it must not leak into a
    let mut rows = Vec::new();
    for k in 0..200 {
        rows.push(drive(&a, k, k + 1, fs).remove(0));
        drive(&b, k, k + 1, fs);
    }
    let bits = |v: &Vec<Vec<f64>>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&ra), bits(&rows));
    // reset: start values back, a fresh run equals the first
    assert_eq!(unsafe { fmi2Reset(a.c) }, 0);
    a.init();
    let again = drive(&a, 0, 200, fs);
    assert_eq!(bits(&ra), bits(&again));
}

#[test]
fn bad_calls_are_errors_with_messages() {
    let f = Fmu::new("bad");
    // step before initialization
    assert_eq!(f.step(0.0, 0.01), fmi2Status_fmi2Error);
    assert!(
        logged("bad")
            .iter()
            .any(|m| m.contains("fmi2DoStep") && m.contains("not allowed")),
        "{:?}",
        logged("bad")
    );
    let g = Fmu::new("bad2");
    g.init();
    assert_eq!(g.set(&[130], &[1.0]), fmi2Status_fmi2Error);
    assert!(logged("bad2").iter().any(|m| m.contains("table.mass")));
    let h = Fmu::new("bad3");
    h.init();
    assert_eq!(h.step(0.5, 0.01), fmi2Status_fmi2Error);
    assert!(logged("bad3").iter().any(|m| m.contains("current time")));
    unsafe {
        assert_eq!(
            fmi2GetReal(
                std::ptr::null_mut(),
                std::ptr::null(),
                0,
                std::ptr::null_mut()
            ),
            fmi2Status_fmi2Error
        );
        let n = CString::new("x").unwrap();
        let guid = CString::new("{wrong}").unwrap();
        let cb = fmi2CallbackFunctions {
            logger: Some(fmi_sys::fmi2::logger::callback_logger_handler),
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: std::ptr::null_mut(),
        };
        assert!(fmi2Instantiate(
            n.as_ptr(),
            fmi2Type_fmi2CoSimulation,
            guid.as_ptr(),
            std::ptr::null(),
            &cb,
            0,
            0
        )
        .is_null());
        // an fmuType that is neither Model Exchange nor Co-Simulation
        let neither: fmi2Type = 7;
        assert!(fmi2Instantiate(
            n.as_ptr(),
            neither,
            CString::new(description_guid(&shaketable::Params::trees_lab()))
                .unwrap()
                .as_ptr(),
            std::ptr::null(),
            &cb,
            0,
            0
        )
        .is_null());
    }
}

/// One FMI call with random arguments.
#[derive(Debug, Clone)]
enum Call {
    Setup(f64),
    Enter,
    Exit,
    SetReal(u32, f64),
    SetInteger(u32, i32),
    SetBoolean(u32, i32),
    GetReal(u32),
    Slope(u32, i32, f64),
    Step(f64, f64),
    GetState,
    SetState,
    Terminate,
    Reset,
    NullGet,
}

fn call() -> impl Strategy<Value = Call> {
    let vr = prop_oneof![0u32..4, 10u32..18, 100u32..182, Just(9999u32)];
    let x = prop_oneof![any::<f64>(), -1e3..1e3f64, Just(f64::NAN), Just(0.0)];
    prop_oneof![
        x.clone().prop_map(Call::Setup),
        Just(Call::Enter),
        Just(Call::Exit),
        (vr.clone(), x.clone()).prop_map(|(v, x)| Call::SetReal(v, x)),
        (vr.clone(), -2i32..5).prop_map(|(v, x)| Call::SetInteger(v, x)),
        (vr.clone(), 0i32..2).prop_map(|(v, x)| Call::SetBoolean(v, x)),
        vr.clone().prop_map(Call::GetReal),
        (vr.clone(), 0i32..3, x.clone()).prop_map(|(v, o, x)| Call::Slope(v, o, x)),
        (
            prop_oneof![Just(0.0), -1.0..1.0f64],
            prop_oneof![Just(1.0 / 512.0), -0.01..0.05f64, Just(f64::NAN)]
        )
            .prop_map(|(t, h)| Call::Step(t, h)),
        Just(Call::GetState),
        Just(Call::SetState),
        Just(Call::Terminate),
        Just(Call::Reset),
        Just(Call::NullGet),
    ]
}

/// Resource locations as an importer might get them wrong: null, random bytes, file URIs
/// with random (and broken, non-ASCII) percent escapes, very long ones.
fn resource_location() -> impl Strategy<Value = Option<Vec<u8>>> {
    let byte = 1u8..=255; // any byte but NUL (a C string)
    let escape = (byte.clone(), byte.clone()).prop_map(|(a, b)| vec![b'%', a, b]);
    let piece = prop_oneof![
        proptest::collection::vec(byte.clone(), 0..8),
        escape,
        Just(b"%".to_vec()),
        Just(b"%C3%A9".to_vec()),
        Just(b"%\xc3\xa9".to_vec()),
        Just(b"/".to_vec()),
    ];
    let prefix = prop_oneof![
        Just(b"file:///".to_vec()),
        Just(b"file://localhost/".to_vec()),
        Just(b"file:/".to_vec()),
        Just(b"file://host/".to_vec()),
        Just(b"FILE:".to_vec()),
        Just(Vec::new()),
    ];
    prop_oneof![
        Just(None),
        proptest::collection::vec(byte, 0..64).prop_map(Some),
        (prefix, proptest::collection::vec(piece, 0..12))
            .prop_map(|(p, ps)| Some([p, ps.concat()].concat())),
        (1usize..20_000).prop_map(|n| Some([b"file:///".to_vec(), vec![b'%'; n]].concat())),
    ]
}

/// fmi2Instantiate with any location: an instance (the defaults, with a logged warning
/// when the location is unusable), or null with a logged reason; never a panic.
fn instantiate_anywhere(name: &str, res: Option<&[u8]>) -> Result<Fmu, TestCaseError> {
    let f = Fmu::open(name, res);
    let msgs = logged(name);
    let shown = res.map(|r| String::from_utf8_lossy(&r[..r.len().min(60)]).into_owned());
    prop_assert!(
        !msgs.iter().any(|m| m.contains("panic")),
        "{shown:?}: {msgs:?}"
    );
    match f {
        Some(f) => Ok(f),
        None => {
            prop_assert!(!msgs.is_empty(), "{shown:?} refused without a message");
            Err(TestCaseError::reject(
                "location refused (an existing folder)",
            ))
        }
    }
}

/// A gain so large its closed loop has no computable poles ends initialisation at once
/// with a logged warning (the pole computation once iterated forever on it, and a
/// refused parameter set was linearised all the same).
#[test]
fn initialisation_with_absurd_gains_ends_at_once_with_a_warning() {
    for (k, x) in [1e300, f64::MAX, -1e300].into_iter().enumerate() {
        let name = format!("huge{k}");
        let f = Fmu::new(&name);
        let start = std::time::Instant::now();
        let s = unsafe {
            assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 0.0, 0, 0.0), 0);
            assert_eq!(fmi2EnterInitializationMode(f.c), 0);
            assert_eq!(f.set(&[100], &[x]), 0);
            fmi2ExitInitializationMode(f.c)
        };
        assert!(
            start.elapsed() < CALL_TIME_LIMIT,
            "{x}: {:?}",
            start.elapsed()
        );
        assert!(
            s == fmi2Status_fmi2Warning || s == fmi2Status_fmi2Error,
            "{x}: status {s}"
        );
        assert!(
            logged(&name)
                .iter()
                .any(|m| m.contains("fmi2ExitInitializationMode")),
            "{x}: {:?}",
            logged(&name)
        );
    }
}

/// Parameters outside the envelope the model describes: unstable or absurd gains, no
/// force feedback, a friction yield far below what a sub-step resolves, a feather-light
/// table, a weak pump.
fn out_of_envelope() -> impl Strategy<Value = (u32, f64)> {
    prop_oneof![
        Just((100, -50.0)),
        Just((100, 1e6)),
        (100u32..106, -1e3..1e3f64),
        Just((105, 0.0)),
        Just((105, -1e-6)),
        Just((133, 1e-9)),
        Just((133, 1e-14)),
        Just((130, 1e-3)),
        Just((124, 1e3)),
        Just((126, 1e3)),
        Just((132, 1e9)),
        Just((121, 1e-9)),
    ]
}

/// Longest accepted wall time of one call: a step must not run away with sub-steps
/// (generous for a loaded 2-core machine; a runaway took minutes).
const CALL_TIME_LIMIT: std::time::Duration = std::time::Duration::from_secs(5);

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]
    /// Out-of-envelope parameters: every step is fmi2OK with finite outputs, or an
    /// error/discard with a logged message; never a panic, never a hang.
    #[test]
    fn out_of_envelope_parameters_step_or_fail_cleanly(
        params in proptest::collection::vec(out_of_envelope(), 1..4),
        res in resource_location(),
        h in prop_oneof![Just(1.0 / 512.0), 1e-4..0.05f64],
        amplitude in prop_oneof![1 => Just(0.0), 4 => 1e-4..0.2f64],
        id in 0u64..u64::MAX,
    ) {
        let name = format!("envelope{id}");
        let f = instantiate_anywhere(&name, res.as_deref())?;
        unsafe {
            prop_assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 0.0, 0, 0.0), 0);
            prop_assert_eq!(fmi2EnterInitializationMode(f.c), 0);
        }
        for (vr, x) in &params {
            prop_assert_eq!(f.set(&[*vr], &[*x]), 0);
        }
        if unsafe { fmi2ExitInitializationMode(f.c) } != 0 {
            prop_assert!(!logged(&name).is_empty(), "refused {params:?} without a message");
            return Ok(());
        }
        for k in 0..60 {
            let t = k as f64 * h;
            prop_assert_eq!(f.set(&[0], &[amplitude * (7.0 * t).sin()]), 0);
            let start = std::time::Instant::now();
            let s = f.step(t, h);
            let took = start.elapsed();
            prop_assert!(took < CALL_TIME_LIMIT, "{params:?}: step {k} took {took:?}");
            if s == fmi2Status_fmi2OK {
                let o = f.get(&OUTPUTS);
                prop_assert!(o.iter().all(|x| x.is_finite()), "{params:?}: step {k} gave {o:?}");
            } else {
                prop_assert!(s == fmi2Status_fmi2Error || s == fmi2Status_fmi2Discard, "status {s}");
                let msgs = logged(&name);
                prop_assert!(msgs.iter().any(|m| m.contains("fmi2DoStep")), "{params:?}: {msgs:?}");
                break;
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]
    #[test]
    fn random_call_sequences_never_crash(calls in proptest::collection::vec(call(), 1..40), id in 0u64..u64::MAX, res in resource_location()) {
        let name = format!("prop{id}");
        let f = instantiate_anywhere(&name, res.as_deref())?;
        let mut state: fmi2FMUstate = std::ptr::null_mut();
        let mut time = 0.0;
        let mut errors = 0usize;
        for c in &calls {
            let start = std::time::Instant::now();
            let s = unsafe {
                match c {
                    Call::Setup(t) => fmi2SetupExperiment(f.c, 0, 0.0, *t, 0, 0.0),
                    Call::Enter => fmi2EnterInitializationMode(f.c),
                    Call::Exit => fmi2ExitInitializationMode(f.c),
                    Call::SetReal(v, x) => fmi2SetReal(f.c, v, 1, x),
                    Call::SetInteger(v, x) => fmi2SetInteger(f.c, v, 1, x),
                    Call::SetBoolean(v, x) => fmi2SetBoolean(f.c, v, 1, x),
                    Call::GetReal(v) => { let mut y = 0.0; fmi2GetReal(f.c, v, 1, &mut y) }
                    Call::Slope(v, o, x) => fmi2SetRealInputDerivatives(f.c, v, 1, o, x),
                    Call::Step(dt, h) => {
                        // mostly at the current time, sometimes off it
                        let t = if *dt == 0.0 { time } else { time + dt };
                        let s = fmi2DoStep(f.c, t, *h, 1);
                        if s == 0 { time = t + h; }
                        s
                    }
                    Call::GetState => fmi2GetFMUstate(f.c, &mut state),
                    Call::SetState => if state.is_null() { 0 } else { fmi2SetFMUstate(f.c, state) },
                    Call::Terminate => fmi2Terminate(f.c),
                    Call::Reset => { time = 0.0; fmi2Reset(f.c) }
                    Call::NullGet => fmi2GetReal(f.c, std::ptr::null(), 2, std::ptr::null_mut()),
                }
            };
            prop_assert!(start.elapsed() < CALL_TIME_LIMIT, "{c:?} took {:?}", start.elapsed());
            prop_assert!(s == fmi2Status_fmi2OK || s == fmi2Status_fmi2Warning || s == fmi2Status_fmi2Error || s == fmi2Status_fmi2Discard, "{c:?} returned {s}");
            // a warning (an unstable loop at initialisation) is logged like an error
            if s == fmi2Status_fmi2Error || s == fmi2Status_fmi2Warning {
                errors += 1;
            }
            if let Call::Setup(t) = c { if s == 0 { time = *t; } }
            if matches!(c, Call::SetState) && s == 0 {
                let mut t = 0.0;
                unsafe { fmi2GetRealStatus(f.c, fmi2StatusKind_fmi2LastSuccessfulTime, &mut t) };
                time = t;
            }
        }
        let msgs = logged(&name);
        prop_assert!(msgs.len() >= errors, "{errors} errors but {} messages", msgs.len());
        unsafe { fmi2FreeFMUstate(f.c, &mut state) };
    }
}
