//! Creating, initialising, terminating and resetting an instance: fmi2Instantiate to
//! fmi2Reset, with the platform and version queries.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use super::*;
use crate::fmi::instance::{Instance, Interface};
use crate::fmi::model_description::guid as description_guid;
use crate::params::Params;
use fmi_sys::fmi2::*;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if nCategories > 0 && categories.is_null() {
                return null_arg(comp, "fmi2SetDebugLogging", "categories");
            }
            comp.instance.logging_on = loggingOn != 0;
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    if functions.is_null() {
        return std::ptr::null_mut();
    }
    // SAFETY: non-null callbacks struct from the importer.
    let cb = unsafe { *functions };
    let name = unsafe { c_str(instanceName) };
    // the component first, so that every refusal below reaches the importer's logger
    let mut comp = Component {
        instance: Instance::new(name.as_deref().unwrap_or(""), Params::trees_lab()),
        logger: cb.logger,
        environment: cb.componentEnvironment,
        name: CString::new(name.clone().unwrap_or_default()).unwrap_or_default(),
    };
    // SAFETY: a non-null location is a NUL-terminated string from the importer.
    let res = (!fmuResourceLocation.is_null())
        .then(|| unsafe { CStr::from_ptr(fmuResourceLocation) }.to_bytes());
    let guid = unsafe { c_str(fmuGUID) };
    let r = catch_unwind(AssertUnwindSafe(|| {
        instantiate(&mut comp, fmuType, guid.as_deref(), res)
    }));
    match r {
        Ok(Ok(())) => {
            comp.instance.logging_on = loggingOn != 0;
            Box::into_raw(Box::new(comp)) as fmi2Component
        }
        Ok(Err(m)) => {
            comp.log(ERROR, "logStatusError", &format!("fmi2Instantiate: {m}"));
            std::ptr::null_mut()
        }
        Err(_) => {
            let m = "fmi2Instantiate: internal error (panic caught at the FMI boundary)";
            comp.log(FATAL, "logStatusFatal", m);
            std::ptr::null_mut()
        }
    }
}

/// The checks of fmi2Instantiate and the start parameters; `Err` is the refusal's reason.
fn instantiate(
    comp: &mut Component,
    fmu_type: fmi2Type,
    guid: Option<&str>,
    resources: Option<&[u8]>,
) -> Result<(), String> {
    if comp.instance.name.is_empty() {
        return Err("instanceName is null or empty".into());
    }
    let interface = match fmu_type {
        x if x == fmi2Type_fmi2CoSimulation => Interface::CoSimulation,
        x if x == fmi2Type_fmi2ModelExchange => Interface::ModelExchange,
        other => {
            return Err(format!(
                "fmuType {other} is neither fmi2ModelExchange nor fmi2CoSimulation"
            ))
        }
    };
    let (params, warning) =
        start_params(resources).map_err(|e| format!("resources/parameters.toml: {e}"))?;
    // the GUID names the description of these start values (one per parameter file)
    let expected = description_guid(&params);
    if guid != Some(expected.as_str()) {
        return Err(format!(
            "GUID {guid:?} does not match {expected}, the GUID of the modelDescription.xml \
             this binary generates for its start values (resources/parameters.toml or the \
             TREES Lab defaults): the FMU's files do not belong together"
        ));
    }
    if let Some(w) = warning {
        comp.log(
            WARNING,
            "logStatusWarning",
            &format!("fmi2Instantiate: {w}"),
        );
    }
    comp.instance = Instance::new(&comp.instance.name, params);
    comp.instance.interface = interface;
    Ok(())
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: c came from Box::into_raw in fmi2Instantiate and is freed once.
        drop(unsafe { Box::from_raw(c as *mut Component) });
    }));
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _toleranceDefined: fmi2Boolean,
    _tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let stop = (stopTimeDefined != 0).then_some(stopTime);
            let r = comp.instance.setup_experiment(startTime, stop);
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let r = comp.instance.enter_initialization_mode();
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    unsafe {
        with(c, |comp| match comp.instance.exit_initialization_mode() {
            // spec section 8: an unstable closed loop is named before the first step
            Ok(Some(w)) => {
                let message = format!("fmi2ExitInitializationMode: {w}");
                comp.log(WARNING, "logStatusWarning", &message);
                WARNING
            }
            r => comp.result(r.map(|_| ())),
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let r = comp.instance.terminate();
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            comp.instance.reset();
            OK
        })
    }
}
