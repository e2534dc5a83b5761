//! Reading and writing variables by value reference: fmi2Get/fmi2Set for Real, Integer,
//! Boolean and String.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use super::*;
use crate::fmi::instance::FmiError;
use crate::fmi::variables::Kind;
use fmi_sys::fmi2::*;

unsafe fn get_values<T: Copy>(
    c: fmi2Component,
    function: &'static str,
    kind: Kind,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut T,
    conv: fn(f64) -> T,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let (Some(vrs), Some(out)) = (slice(vr, nvr), slice_mut(value, nvr)) else {
                return null_arg(comp, function, "vr or value");
            };
            let mut tmp = vec![0.0; nvr];
            match comp.instance.get(function, kind, vrs, &mut tmp) {
                Ok(()) => {
                    for (o, x) in out.iter_mut().zip(tmp) {
                        *o = conv(x);
                    }
                    OK
                }
                Err(e) => {
                    // a refused get does not end the instance (it changes nothing)
                    comp.log(ERROR, "logStatusError", &e.to_string());
                    ERROR
                }
            }
        })
    }
}

unsafe fn set_values<T: Copy>(
    c: fmi2Component,
    function: &'static str,
    kind: Kind,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const T,
    conv: fn(T) -> f64,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let (Some(vrs), Some(vals)) = (slice(vr, nvr), slice(value, nvr)) else {
                return null_arg(comp, function, "vr or value");
            };
            let v: Vec<f64> = vals.iter().map(|x| conv(*x)).collect();
            let r = comp.instance.set(function, kind, vrs, &v);
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    unsafe { get_values(c, "fmi2GetReal", Kind::Real, vr, nvr, value, |x| x) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    unsafe {
        get_values(c, "fmi2GetInteger", Kind::Integer, vr, nvr, value, |x| {
            x as fmi2Integer
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        get_values(c, "fmi2GetBoolean", Kind::Boolean, vr, nvr, value, |x| {
            (x != 0.0) as fmi2Boolean
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if nvr == 0 {
                return OK;
            }
            if vr.is_null() || value.is_null() {
                return null_arg(comp, "fmi2GetString", "vr or value");
            }
            // SAFETY: nvr > 0 and vr non-null.
            let first = *vr;
            comp.log(ERROR, "logStatusError", &format!("fmi2GetString: unknown value reference {first} (the FMU has no String variables)"));
            ERROR
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    unsafe { set_values(c, "fmi2SetReal", Kind::Real, vr, nvr, value, |x| x) }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    unsafe {
        set_values(c, "fmi2SetInteger", Kind::Integer, vr, nvr, value, |x| {
            x as f64
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    unsafe {
        set_values(c, "fmi2SetBoolean", Kind::Boolean, vr, nvr, value, |x| {
            if x != 0 {
                1.0
            } else {
                0.0
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if nvr == 0 {
                return OK;
            }
            if vr.is_null() || value.is_null() {
                return null_arg(comp, "fmi2SetString", "vr or value");
            }
            let first = *vr;
            comp.fail(FmiError {
                function: "fmi2SetString",
                message: format!(
                    "unknown value reference {first} (the FMU has no String variables)"
                ),
            })
        })
    }
}
