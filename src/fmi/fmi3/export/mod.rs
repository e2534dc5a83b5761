//! The FMI 3.0 Co-Simulation C ABI over [`Instance`], in the same shared library as the
//! FMI 2.0 functions (their names differ): every function of `fmi3FunctionTypes.h` is
//! exported with the exact `fmi-sys` signature (checked at compile time at the end), so
//! any importer can load the binary. Model Exchange, Scheduled Execution, clocks, event
//! mode and derivatives are refused with a logged message. No panic crosses the boundary.//!
//! Here: the component, the argument helpers and the signature checks; `lifecycle.rs`,
//! `values.rs`, `state.rs`: the functions by concern; `refused.rs`: those not offered.

#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]
mod lifecycle;
mod refused;
mod state;
mod values;

pub use lifecycle::*;
pub use refused::*;
pub use state::*;
pub use values::*;

use crate::fmi::instance::{FmiError, Instance, Phase};
use fmi_sys::fmi3::*;
use std::ffi::{CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

const OK: fmi3Status = fmi3Status_fmi3OK;
const WARNING: fmi3Status = fmi3Status_fmi3Warning;
const ERROR: fmi3Status = fmi3Status_fmi3Error;
const FATAL: fmi3Status = fmi3Status_fmi3Fatal;

/// The instance plus the importer's logger.
struct Component {
    instance: Instance,
    logger: fmi3LogMessageCallback,
    environment: fmi3InstanceEnvironment,
}

/// The FMI 3.0 name of a function the shared instance reports in FMI 2.0 words.
fn fmi3_name(function: &str) -> String {
    match function {
        "fmi2GetReal" => "fmi3GetFloat64".into(),
        "fmi2SetReal" => "fmi3SetFloat64".into(),
        "fmi2GetInteger" => "fmi3GetInt64".into(),
        "fmi2SetInteger" => "fmi3SetInt64".into(),
        "fmi2SetupExperiment" => "fmi3EnterInitializationMode".into(),
        "fmi2SetFMUstate" => "fmi3SetFMUState".into(),
        other => other.replacen("fmi2", "fmi3", 1),
    }
}

impl Component {
    fn log(&self, status: fmi3Status, category: &str, message: &str) {
        if let Some(logger) = self.logger {
            let cat = CString::new(category).unwrap_or_default();
            let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
            // SAFETY: the importer's logger, with NUL-terminated strings it may copy.
            unsafe { logger(self.environment, status, cat.as_ptr(), msg.as_ptr()) };
        }
    }

    fn fail(&mut self, e: FmiError) -> fmi3Status {
        let message = format!("{}: {}", fmi3_name(e.function), e.message);
        self.log(ERROR, "logStatusError", &message);
        self.instance.phase = Phase::Error;
        ERROR
    }

    fn result(&mut self, r: Result<(), FmiError>) -> fmi3Status {
        match r {
            Ok(()) => OK,
            Err(e) => self.fail(e),
        }
    }
}

/// Run `f` on the instance; a null instance is an error, a panic fatal.
unsafe fn with(i: fmi3Instance, f: impl FnOnce(&mut Component) -> fmi3Status) -> fmi3Status {
    if i.is_null() {
        return ERROR;
    }
    // SAFETY: a non-null instance is a Box<Component> from fmi3InstantiateCoSimulation.
    let comp = unsafe { &mut *(i as *mut Component) };
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

fn null_arg(comp: &mut Component, function: &'static str, what: &str) -> fmi3Status {
    comp.fail(FmiError {
        function,
        message: format!("{what} is a null pointer"),
    })
}

/// A function this FMU does not offer: logged, fmi3Error, the instance unchanged.
unsafe fn refuse(i: fmi3Instance, function: &str, why: &str) -> fmi3Status {
    unsafe {
        with(i, |comp| {
            comp.log(ERROR, "logStatusError", &format!("{function}: {why}"));
            ERROR
        })
    }
}

const CO_SIMULATION_ONLY: &str =
    "not supported: ShakeTable3.fmu is FMI 3.0 Co-Simulation without event mode, clocks or \
     derivatives (Model Exchange is in the FMI 2.0 ShakeTable.fmu)";

unsafe fn c_str(p: fmi3String) -> Option<String> {
    // SAFETY: the importer passes NUL-terminated strings.
    (!p.is_null()).then(|| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}

// Compile-time check of the implemented exports against the fmi-sys FMI 3.0 types.
const _: fmi3GetVersionTYPE = Some(fmi3GetVersion);
const _: fmi3SetDebugLoggingTYPE = Some(fmi3SetDebugLogging);
const _: fmi3InstantiateCoSimulationTYPE = Some(fmi3InstantiateCoSimulation);
const _: fmi3InstantiateModelExchangeTYPE = Some(fmi3InstantiateModelExchange);
const _: fmi3InstantiateScheduledExecutionTYPE = Some(fmi3InstantiateScheduledExecution);
const _: fmi3FreeInstanceTYPE = Some(fmi3FreeInstance);
const _: fmi3EnterInitializationModeTYPE = Some(fmi3EnterInitializationMode);
const _: fmi3ExitInitializationModeTYPE = Some(fmi3ExitInitializationMode);
const _: fmi3TerminateTYPE = Some(fmi3Terminate);
const _: fmi3ResetTYPE = Some(fmi3Reset);
const _: fmi3DoStepTYPE = Some(fmi3DoStep);
const _: fmi3GetFloat64TYPE = Some(fmi3GetFloat64);
const _: fmi3SetFloat64TYPE = Some(fmi3SetFloat64);
const _: fmi3GetInt64TYPE = Some(fmi3GetInt64);
const _: fmi3SetInt64TYPE = Some(fmi3SetInt64);
const _: fmi3GetBooleanTYPE = Some(fmi3GetBoolean);
const _: fmi3SetBooleanTYPE = Some(fmi3SetBoolean);
const _: fmi3GetFMUStateTYPE = Some(fmi3GetFMUState);
const _: fmi3SetFMUStateTYPE = Some(fmi3SetFMUState);
const _: fmi3FreeFMUStateTYPE = Some(fmi3FreeFMUState);
const _: fmi3SerializedFMUStateSizeTYPE = Some(fmi3SerializedFMUStateSize);
const _: fmi3SerializeFMUStateTYPE = Some(fmi3SerializeFMUState);
const _: fmi3DeserializeFMUStateTYPE = Some(fmi3DeserializeFMUState);
