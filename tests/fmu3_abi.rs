//! The FMI 3.0 Co-Simulation functions through their C ABI in-process (issue 18 part 4):
//! the instantiation token belongs to the start values, steps are bit-identical to the
//! library's simulator, FMU states round-trip, what the FMU does not offer is refused.

use fmi_sys::fmi3::*;
use shaketable::fmi::fmi3::export::*;
use shaketable::fmi::fmi3::model_description::{instantiation_token, TIME_VR};
use shaketable::fmi::variables::inputs_from;
use shaketable::solver::DEFAULT_MAX_SUBSTEP_S;
use shaketable::{Model, Params, SensorNoise, Simulator};
use std::ffi::{c_void, CStr, CString};
use std::sync::Mutex;

static LOG: Mutex<Vec<String>> = Mutex::new(Vec::new());

unsafe extern "C" fn logger(
    _env: fmi3InstanceEnvironment,
    _status: fmi3Status,
    _category: fmi3String,
    message: fmi3String,
) {
    let m = unsafe { CStr::from_ptr(message) }
        .to_string_lossy()
        .into_owned();
    LOG.lock().unwrap().push(m);
}

const OUTPUTS: [u32; 8] = [10, 11, 12, 13, 14, 15, 16, 17];
const INPUTS: [u32; 4] = [0, 1, 2, 3];

fn instantiate(name: &str, token: &str) -> fmi3Instance {
    let n = CString::new(name).unwrap();
    let t = CString::new(token).unwrap();
    unsafe {
        fmi3InstantiateCoSimulation(
            n.as_ptr(),
            t.as_ptr(),
            std::ptr::null(),
            false,
            false,
            false,
            false,
            std::ptr::null(),
            0,
            std::ptr::null_mut::<c_void>(),
            Some(logger),
            None,
        )
    }
}

fn get(i: fmi3Instance, vrs: &[u32]) -> Vec<f64> {
    let mut v = vec![0.0; vrs.len()];
    let s = unsafe { fmi3GetFloat64(i, vrs.as_ptr(), vrs.len(), v.as_mut_ptr(), v.len()) };
    assert_eq!(s, fmi3Status_fmi3OK);
    v
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn steps_match_the_library_simulator_bit_for_bit() {
    let i = instantiate("steps", &instantiation_token(&Params::trees_lab()));
    assert!(!i.is_null(), "{:?}", LOG.lock().unwrap());
    unsafe {
        assert_eq!(
            fmi3EnterInitializationMode(i, false, 0.0, 0.0, false, 0.0),
            fmi3Status_fmi3OK
        );
        assert_eq!(fmi3ExitInitializationMode(i), fmi3Status_fmi3OK);
    }
    let mut sim = Simulator::new(Model::new(&Params::trees_lab()), 0.0, DEFAULT_MAX_SUBSTEP_S);
    let h = 1.0 / 512.0;
    let mut t = 0.0;
    for k in 0..200 {
        let w = 2.0 * std::f64::consts::PI * 2.0;
        let tk = k as f64 * h;
        let u = [0.01 * (w * tk).sin(), 0.01 * w * (w * tk).cos(), 0.0, 0.0];
        unsafe {
            fmi3SetFloat64(i, INPUTS.as_ptr(), 4, u.as_ptr(), 4);
            let (mut event, mut stop, mut early, mut last) = (true, true, true, 0.0);
            let s = fmi3DoStep(i, t, h, true, &mut event, &mut stop, &mut early, &mut last);
            assert_eq!(s, fmi3Status_fmi3OK);
            assert!(!event && !stop && !early);
            assert_eq!(last, t + h);
        }
        sim.advance(
            h,
            &inputs_from(&u),
            &inputs_from(&u),
            &SensorNoise::default(),
        );
        t += h;
        let o = sim.outputs(&inputs_from(&u), &SensorNoise::default());
        let want = [
            o.displacement_m,
            o.velocity_m_s,
            o.acceleration_m_s2,
            o.actuator_force_n,
        ];
        assert_eq!(bits(&get(i, &OUTPUTS[..4])), bits(&want), "step {k}");
    }
    assert_eq!(get(i, &[TIME_VR]), vec![t]);
    unsafe { fmi3FreeInstance(i) };
}

#[test]
fn the_token_belongs_to_the_start_values() {
    LOG.lock().unwrap().clear();
    assert!(instantiate("wrong", "{not-the-token}").is_null());
    assert!(LOG
        .lock()
        .unwrap()
        .iter()
        .any(|m| m.contains("instantiationToken") && m.contains("start values")));
    let mut heavier = Params::trees_lab();
    heavier.table.mass_kg *= 2.0;
    assert_ne!(
        instantiation_token(&heavier),
        instantiation_token(&Params::trees_lab())
    );
}

#[test]
fn fmu_state_round_trips_and_unoffered_functions_are_refused() {
    let i = instantiate("state", &instantiation_token(&Params::trees_lab()));
    unsafe {
        fmi3EnterInitializationMode(i, false, 0.0, 0.0, false, 0.0);
        fmi3ExitInitializationMode(i);
        let u = [0.002, 0.0, 0.0, 0.0];
        fmi3SetFloat64(i, INPUTS.as_ptr(), 4, u.as_ptr(), 4);
        let (mut e, mut s, mut r, mut l) = (false, false, false, 0.0);
        let h = 1.0 / 512.0;
        let mut state: fmi3FMUState = std::ptr::null_mut();
        for k in 0..20 {
            fmi3DoStep(i, k as f64 * h, h, true, &mut e, &mut s, &mut r, &mut l);
        }
        assert_eq!(fmi3GetFMUState(i, &mut state), fmi3Status_fmi3OK);
        let mut size = 0;
        fmi3SerializedFMUStateSize(i, state, &mut size);
        let mut bytes = vec![0u8; size];
        assert_eq!(
            fmi3SerializeFMUState(i, state, bytes.as_mut_ptr(), size),
            fmi3Status_fmi3OK
        );
        let before = get(i, &OUTPUTS);
        for k in 20..40 {
            fmi3DoStep(i, k as f64 * h, h, true, &mut e, &mut s, &mut r, &mut l);
        }
        assert_ne!(get(i, &OUTPUTS), before);
        let mut restored: fmi3FMUState = std::ptr::null_mut();
        assert_eq!(
            fmi3DeserializeFMUState(i, bytes.as_ptr(), size, &mut restored),
            fmi3Status_fmi3OK
        );
        assert_eq!(fmi3SetFMUState(i, restored), fmi3Status_fmi3OK);
        assert_eq!(bits(&get(i, &OUTPUTS)), bits(&before));
        fmi3FreeFMUState(i, &mut state);
        fmi3FreeFMUState(i, &mut restored);
        assert!(state.is_null() && restored.is_null());
        // the enumeration travels as Int64; a value outside it is refused
        let mut model = [0i64];
        let vr = [110u32];
        assert_eq!(
            fmi3GetInt64(i, vr.as_ptr(), 1, model.as_mut_ptr(), 1),
            fmi3Status_fmi3OK
        );
        assert_eq!(model[0], 3);
        // Model Exchange is not in this FMU: a clear refusal
        LOG.lock().unwrap().clear();
        assert_eq!(fmi3EnterContinuousTimeMode(i), fmi3Status_fmi3Error);
        assert!(LOG
            .lock()
            .unwrap()
            .iter()
            .any(|m| m.contains("fmi3EnterContinuousTimeMode")));
        fmi3FreeInstance(i);
    }
}
