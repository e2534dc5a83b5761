//! Creating, initialising, stepping, terminating and resetting an instance:
//! fmi3InstantiateCoSimulation to fmi3Reset and fmi3DoStep (the other interfaces'
//! instantiation refused), with the version query and debug logging.

#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use super::*;
use crate::fmi::export::start_params;
use crate::fmi::fmi3::model_description::instantiation_token;
use crate::fmi::instance::Instance;
use fmi_sys::fmi3::*;
use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    loggingOn: fmi3Boolean,
    _nCategories: usize,
    _categories: *const fmi3String,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            comp.instance.logging_on = loggingOn;
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    _earlyReturnAllowed: fmi3Boolean,
    _requiredIntermediateVariables: *const fmi3ValueReference,
    _nRequiredIntermediateVariables: usize,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    _intermediateUpdate: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    let name = unsafe { c_str(instanceName) }.unwrap_or_default();
    let mut comp = Component {
        instance: Instance::new(&name, crate::Params::trees_lab()),
        logger: logMessage,
        environment: instanceEnvironment,
    };
    let token = unsafe { c_str(instantiationToken) };
    let resources = (!resourcePath.is_null())
        // SAFETY: a NUL-terminated path from the importer.
        .then(|| unsafe { CStr::from_ptr(resourcePath) }.to_bytes());
    let r = catch_unwind(AssertUnwindSafe(|| {
        instantiate(&mut comp, token.as_deref(), eventModeUsed, resources)
    }));
    match r {
        Ok(Ok(())) => {
            comp.instance.logging_on = loggingOn;
            Box::into_raw(Box::new(comp)) as fmi3Instance
        }
        Ok(Err(m)) => {
            comp.log(
                ERROR,
                "logStatusError",
                &format!("fmi3InstantiateCoSimulation: {m}"),
            );
            std::ptr::null_mut()
        }
        Err(_) => std::ptr::null_mut(),
    }
}

/// The checks of fmi3InstantiateCoSimulation; `Err` is the refusal's reason.
fn instantiate(
    comp: &mut Component,
    token: Option<&str>,
    event_mode_used: bool,
    resources: Option<&[u8]>,
) -> Result<(), String> {
    if comp.instance.name.is_empty() {
        return Err("instanceName is null or empty".into());
    }
    if event_mode_used {
        return Err("eventModeUsed: this FMU has no event mode (hasEventMode = false)".into());
    }
    let (params, warning) =
        start_params(resources).map_err(|e| format!("resources/parameters.toml: {e}"))?;
    if let Some(w) = warning {
        let w = w.replace("fmuResourceLocation", "resourcePath");
        comp.log(
            WARNING,
            "logStatusWarning",
            &format!("fmi3InstantiateCoSimulation: {w}"),
        );
    }
    let expected = instantiation_token(&params);
    if token != Some(expected.as_str()) {
        return Err(format!(
            "instantiationToken {token:?} does not match {expected}, the token of the \
             modelDescription.xml this binary generates for its start values: the FMU's \
             files do not belong together"
        ));
    }
    comp.instance = Instance::new(&comp.instance.name, params);
    Ok(())
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    _instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
) -> fmi3Instance {
    let comp = Component {
        instance: Instance::new("", crate::Params::trees_lab()),
        logger: logMessage,
        environment: instanceEnvironment,
    };
    comp.log(
        ERROR,
        "logStatusError",
        &format!("fmi3InstantiateModelExchange: {CO_SIMULATION_ONLY}"),
    );
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    _clockUpdate: fmi3ClockUpdateCallback,
    _lockPreemption: fmi3LockPreemptionCallback,
    _unlockPreemption: fmi3UnlockPreemptionCallback,
) -> fmi3Instance {
    let comp = Component {
        instance: Instance::new("", crate::Params::trees_lab()),
        logger: logMessage,
        environment: instanceEnvironment,
    };
    let m = format!("fmi3InstantiateScheduledExecution: {CO_SIMULATION_ONLY}");
    comp.log(ERROR, "logStatusError", &m);
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    if !instance.is_null() {
        // SAFETY: the Box made by fmi3InstantiateCoSimulation, freed once.
        let _ = catch_unwind(AssertUnwindSafe(|| unsafe {
            drop(Box::from_raw(instance as *mut Component))
        }));
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    _toleranceDefined: fmi3Boolean,
    _tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let stop = stopTimeDefined.then_some(stopTime);
            let r = comp
                .instance
                .setup_experiment(startTime, stop)
                .and_then(|_| comp.instance.enter_initialization_mode());
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            match comp.instance.exit_initialization_mode() {
                // spec section 8: an unstable closed loop is named before the first step
                Ok(Some(w)) => {
                    let message = format!("fmi3ExitInitializationMode: {w}");
                    comp.log(WARNING, "logStatusWarning", &message);
                    WARNING
                }
                r => comp.result(r.map(|_| ())),
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let r = comp.instance.terminate();
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            comp.instance.reset();
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let r = comp
                .instance
                .do_step(currentCommunicationPoint, communicationStepSize);
            let status = comp.result(r);
            let put = |p: *mut bool, v: bool| {
                if !p.is_null() {
                    *p = v;
                }
            };
            put(eventHandlingNeeded, false);
            put(terminateSimulation, status != OK);
            put(earlyReturn, false);
            if !lastSuccessfulTime.is_null() {
                *lastSuccessfulTime = comp.instance.time_s;
            }
            status
        })
    }
}
