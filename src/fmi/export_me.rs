//! The FMI 2.0 Model Exchange C ABI over [`super::model_exchange`]: the same checks,
//! logging and panic barrier as the Co-Simulation exports (`export.rs`).

#![allow(non_snake_case, clippy::missing_safety_doc)]

use super::export::{null_arg, slice, slice_mut, with, Component, OK};
use super::instance::FmiError;
use fmi_sys::fmi2::*;

/// Run an instance method that fills an array of `n` reals at `p`.
unsafe fn fill(
    c: fmi2Component,
    function: &'static str,
    p: *mut fmi2Real,
    n: usize,
    f: impl FnOnce(&Component, &mut [f64]) -> Result<(), FmiError>,
) -> fmi2Status {
    unsafe {
        with(c, |comp| match slice_mut(p, n) {
            Some(out) => {
                let r = f(comp, out);
                comp.result(r)
            }
            None => null_arg(comp, function, "the value array"),
        })
    }
}

/// Write `value` through an fmi2Boolean out-pointer the importer may pass as null.
unsafe fn put(p: *mut fmi2Boolean, value: bool) {
    if !p.is_null() {
        // SAFETY: a non-null out-pointer from the importer.
        unsafe { *p = value as fmi2Boolean };
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let r = comp.instance.enter_event_mode();
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2NewDiscreteStates(
    c: fmi2Component,
    fmi2eventInfo: *mut fmi2EventInfo,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if fmi2eventInfo.is_null() {
                return null_arg(comp, "fmi2NewDiscreteStates", "fmi2eventInfo");
            }
            let r = comp.instance.new_discrete_states();
            let status = comp.result(r);
            if status == OK {
                // no discrete state, no time event: the event only restarts integration
                *fmi2eventInfo = fmi2EventInfo {
                    newDiscreteStatesNeeded: 0,
                    terminateSimulation: 0,
                    nominalsOfContinuousStatesChanged: 0,
                    valuesOfContinuousStatesChanged: 0,
                    nextEventTimeDefined: 0,
                    nextEventTime: 0.0,
                };
            }
            status
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let r = comp.instance.enter_continuous_time_mode();
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: fmi2Component,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    enterEventMode: *mut fmi2Boolean,
    terminateSimulation: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let r = comp.instance.completed_integrator_step();
            let status = comp.result(r);
            put(enterEventMode, false);
            put(terminateSimulation, status != OK);
            status
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let r = comp.instance.set_time(time);
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: fmi2Component,
    x: *const fmi2Real,
    nx: usize,
) -> fmi2Status {
    unsafe {
        with(c, |comp| match slice(x, nx) {
            Some(x) => {
                let r = comp.instance.set_continuous_states(x);
                comp.result(r)
            }
            None => null_arg(comp, "fmi2SetContinuousStates", "x"),
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetDerivatives(
    c: fmi2Component,
    derivatives: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    unsafe {
        fill(c, "fmi2GetDerivatives", derivatives, nx, |comp, out| {
            comp.instance.derivatives(out)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetEventIndicators(
    c: fmi2Component,
    eventIndicators: *mut fmi2Real,
    ni: usize,
) -> fmi2Status {
    unsafe {
        fill(
            c,
            "fmi2GetEventIndicators",
            eventIndicators,
            ni,
            |comp, out| comp.instance.event_indicators(out),
        )
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetContinuousStates(
    c: fmi2Component,
    x: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    unsafe {
        fill(c, "fmi2GetContinuousStates", x, nx, |comp, out| {
            comp.instance.continuous_states(out)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: fmi2Component,
    x_nominal: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    unsafe {
        fill(
            c,
            "fmi2GetNominalsOfContinuousStates",
            x_nominal,
            nx,
            |comp, out| comp.instance.state_nominals(out),
        )
    }
}

// Compile-time check of every export against the fmi-sys FMI 2.0 types.
const _: fmi2EnterEventModeTYPE = Some(fmi2EnterEventMode);
const _: fmi2NewDiscreteStatesTYPE = Some(fmi2NewDiscreteStates);
const _: fmi2EnterContinuousTimeModeTYPE = Some(fmi2EnterContinuousTimeMode);
const _: fmi2CompletedIntegratorStepTYPE = Some(fmi2CompletedIntegratorStep);
const _: fmi2SetTimeTYPE = Some(fmi2SetTime);
const _: fmi2SetContinuousStatesTYPE = Some(fmi2SetContinuousStates);
const _: fmi2GetDerivativesTYPE = Some(fmi2GetDerivatives);
const _: fmi2GetEventIndicatorsTYPE = Some(fmi2GetEventIndicators);
const _: fmi2GetContinuousStatesTYPE = Some(fmi2GetContinuousStates);
const _: fmi2GetNominalsOfContinuousStatesTYPE = Some(fmi2GetNominalsOfContinuousStates);
