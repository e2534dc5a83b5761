//! The FMI 2.0 Co-Simulation C ABI over [`Instance`]: every function a CS FMU must export,
//! with the exact `fmi-sys` signatures (checked at compile time below). Each body runs
//! under `catch_unwind`: no panic crosses the boundary. Errors are logged through the
//! importer's logger with the function name and the reason, and return fmi2Error.//!
//! Here: the component, the argument helpers and the signature checks; `lifecycle.rs`,
//! `values.rs`, `state.rs`, `stepping.rs`: the functions by concern; `resources.rs`: the
//! start parameters from the resource location.

#![allow(non_snake_case, clippy::missing_safety_doc)]
mod lifecycle;
mod resources;
mod state;
mod stepping;
mod values;

pub use lifecycle::*;
pub use resources::*;
pub use state::*;
pub use stepping::*;
pub use values::*;

use super::instance::{FmiError, Instance, Phase};
use fmi_sys::fmi2::*;
use std::ffi::{CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

pub(super) const OK: fmi2Status = fmi2Status_fmi2OK;
const WARNING: fmi2Status = fmi2Status_fmi2Warning;
const DISCARD: fmi2Status = fmi2Status_fmi2Discard;
pub(super) const ERROR: fmi2Status = fmi2Status_fmi2Error;
const FATAL: fmi2Status = fmi2Status_fmi2Fatal;

/// The C-side component: the instance plus the importer's callbacks.
pub(super) struct Component {
    pub(super) instance: Instance,
    logger: fmi2CallbackLogger,
    environment: fmi2ComponentEnvironment,
    name: CString,
}

impl Component {
    fn log(&self, status: fmi2Status, category: &str, message: &str) {
        if let Some(logger) = self.logger {
            let cat = CString::new(category).unwrap_or_default();
            let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
            // SAFETY: the logger is the importer's, called with a "%s" format and one string.
            unsafe {
                logger(
                    self.environment,
                    self.name.as_ptr(),
                    status,
                    cat.as_ptr(),
                    c"%s".as_ptr(),
                    msg.as_ptr(),
                );
            }
        }
    }

    fn fail(&mut self, e: FmiError) -> fmi2Status {
        self.log(ERROR, "logStatusError", &e.to_string());
        // FMI 2.0: after fmi2Error the instance only accepts get, reset and free
        self.instance.phase = Phase::Error;
        ERROR
    }

    pub(super) fn result(&mut self, r: Result<(), FmiError>) -> fmi2Status {
        match r {
            Ok(()) => OK,
            Err(e) => self.fail(e),
        }
    }
}

/// Run `f` on the component, turning a null component and any panic into fmi2Error/Fatal.
pub(super) unsafe fn with(
    c: fmi2Component,
    f: impl FnOnce(&mut Component) -> fmi2Status,
) -> fmi2Status {
    if c.is_null() {
        return ERROR;
    }
    // SAFETY: a non-null component is a Box<Component> from fmi2Instantiate.
    let comp = unsafe { &mut *(c as *mut Component) };
    match catch_unwind(AssertUnwindSafe(|| f(comp))) {
        Ok(s) => s,
        Err(_) => {
            comp.log(
                FATAL,
                "logStatusFatal",
                "internal error (panic caught at the FMI boundary)",
            );
            FATAL
        }
    }
}

/// A slice from an FMI array argument; `None` for a null pointer with a non-zero length.
pub(super) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: the importer promises n elements at p.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

pub(super) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: as above.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

pub(super) fn null_arg(comp: &mut Component, function: &'static str, what: &str) -> fmi2Status {
    comp.fail(FmiError {
        function,
        message: format!("{what} is a null pointer"),
    })
}

unsafe fn c_str(p: fmi2String) -> Option<String> {
    if p.is_null() {
        None
    } else {
        // SAFETY: the importer passes NUL-terminated strings.
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }
}

// Compile-time check of every export against the fmi-sys FMI 2.0 types.
const _: fmi2GetTypesPlatformTYPE = Some(fmi2GetTypesPlatform);
const _: fmi2GetVersionTYPE = Some(fmi2GetVersion);
const _: fmi2SetDebugLoggingTYPE = Some(fmi2SetDebugLogging);
const _: fmi2InstantiateTYPE = Some(fmi2Instantiate);
const _: fmi2FreeInstanceTYPE = Some(fmi2FreeInstance);
const _: fmi2SetupExperimentTYPE = Some(fmi2SetupExperiment);
const _: fmi2EnterInitializationModeTYPE = Some(fmi2EnterInitializationMode);
const _: fmi2ExitInitializationModeTYPE = Some(fmi2ExitInitializationMode);
const _: fmi2TerminateTYPE = Some(fmi2Terminate);
const _: fmi2ResetTYPE = Some(fmi2Reset);
const _: fmi2GetRealTYPE = Some(fmi2GetReal);
const _: fmi2GetIntegerTYPE = Some(fmi2GetInteger);
const _: fmi2GetBooleanTYPE = Some(fmi2GetBoolean);
const _: fmi2GetStringTYPE = Some(fmi2GetString);
const _: fmi2SetRealTYPE = Some(fmi2SetReal);
const _: fmi2SetIntegerTYPE = Some(fmi2SetInteger);
const _: fmi2SetBooleanTYPE = Some(fmi2SetBoolean);
const _: fmi2SetStringTYPE = Some(fmi2SetString);
const _: fmi2GetFMUstateTYPE = Some(fmi2GetFMUstate);
const _: fmi2SetFMUstateTYPE = Some(fmi2SetFMUstate);
const _: fmi2FreeFMUstateTYPE = Some(fmi2FreeFMUstate);
const _: fmi2SerializedFMUstateSizeTYPE = Some(fmi2SerializedFMUstateSize);
const _: fmi2SerializeFMUstateTYPE = Some(fmi2SerializeFMUstate);
const _: fmi2DeSerializeFMUstateTYPE = Some(fmi2DeSerializeFMUstate);
const _: fmi2GetDirectionalDerivativeTYPE = Some(fmi2GetDirectionalDerivative);
const _: fmi2SetRealInputDerivativesTYPE = Some(fmi2SetRealInputDerivatives);
const _: fmi2GetRealOutputDerivativesTYPE = Some(fmi2GetRealOutputDerivatives);
const _: fmi2DoStepTYPE = Some(fmi2DoStep);
const _: fmi2CancelStepTYPE = Some(fmi2CancelStep);
const _: fmi2GetStatusTYPE = Some(fmi2GetStatus);
const _: fmi2GetRealStatusTYPE = Some(fmi2GetRealStatus);
const _: fmi2GetIntegerStatusTYPE = Some(fmi2GetIntegerStatus);
const _: fmi2GetBooleanStatusTYPE = Some(fmi2GetBooleanStatus);
const _: fmi2GetStringStatusTYPE = Some(fmi2GetStringStatus);
