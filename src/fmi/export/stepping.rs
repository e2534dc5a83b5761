//! Stepping: fmi2DoStep, fmi2CancelStep, the input and output derivatives, and the
//! status queries; the directional derivative is not supported.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use super::*;
use crate::fmi::instance::FmiError;
use fmi_sys::fmi2::*;

fn unsupported(c: fmi2Component, function: &'static str, why: &str) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            comp.fail(FmiError {
                function,
                message: why.to_string(),
            })
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _vUnknown_ref: *const fmi2ValueReference,
    _nUnknown: usize,
    _vKnown_ref: *const fmi2ValueReference,
    _nKnown: usize,
    _dvKnown: *const fmi2Real,
    _dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    unsupported(
        c,
        "fmi2GetDirectionalDerivative",
        "not provided (providesDirectionalDerivative=false)",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let (Some(v), Some(o), Some(x)) =
                (slice(vr, nvr), slice(order, nvr), slice(value, nvr))
            else {
                return null_arg(comp, "fmi2SetRealInputDerivatives", "vr, order or value");
            };
            let r = comp.instance.set_input_derivatives(v, o, x);
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    unsupported(
        c,
        "fmi2GetRealOutputDerivatives",
        "output derivatives are not provided (maxOutputDerivativeOrder=0)",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let r = comp
                .instance
                .do_step(currentCommunicationPoint, communicationStepSize);
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    unsupported(
        c,
        "fmi2CancelStep",
        "fmi2DoStep is synchronous (canRunAsynchronuously=false): nothing to cancel",
    )
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Status,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if value.is_null() {
                return null_arg(comp, "fmi2GetStatus", "value");
            }
            if s == fmi2StatusKind_fmi2DoStepStatus {
                *value = OK;
                OK
            } else {
                comp.log(
                    DISCARD,
                    "logStatusDiscard",
                    &format!("fmi2GetStatus: status kind {s} is not available"),
                );
                DISCARD
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if value.is_null() {
                return null_arg(comp, "fmi2GetRealStatus", "value");
            }
            if s == fmi2StatusKind_fmi2LastSuccessfulTime {
                *value = comp.instance.time_s;
                OK
            } else {
                comp.log(
                    DISCARD,
                    "logStatusDiscard",
                    &format!("fmi2GetRealStatus: status kind {s} is not available"),
                );
                DISCARD
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if value.is_null() {
                return null_arg(comp, "fmi2GetIntegerStatus", "value");
            }
            comp.log(
                DISCARD,
                "logStatusDiscard",
                &format!("fmi2GetIntegerStatus: status kind {s} is not available"),
            );
            DISCARD
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if value.is_null() {
                return null_arg(comp, "fmi2GetBooleanStatus", "value");
            }
            if s == fmi2StatusKind_fmi2Terminated {
                *value = 0;
                OK
            } else {
                comp.log(
                    DISCARD,
                    "logStatusDiscard",
                    &format!("fmi2GetBooleanStatus: status kind {s} is not available"),
                );
                DISCARD
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if value.is_null() {
                return null_arg(comp, "fmi2GetStringStatus", "value");
            }
            if s == fmi2StatusKind_fmi2PendingStatus {
                *value = c"".as_ptr();
                OK
            } else {
                comp.log(
                    DISCARD,
                    "logStatusDiscard",
                    &format!("fmi2GetStringStatus: status kind {s} is not available"),
                );
                DISCARD
            }
        })
    }
}
