//! Reading and writing variables by value reference: fmi3Get/fmi3Set for Float64, Int64
//! and Boolean (the independent variable `time` readable).

#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use super::*;
use crate::fmi::export::{slice, slice_mut};
use crate::fmi::fmi3::model_description::TIME_VR;
use crate::fmi::instance::FmiError;
use crate::fmi::variables::Kind;
use fmi_sys::fmi3::*;

/// Read `vrs` of kind `kind` as f64 (the independent variable `time` included).
unsafe fn get_values<T: Copy>(
    instance: fmi3Instance,
    function: &'static str,
    kind: Kind,
    vr: *const fmi3ValueReference,
    nvr: usize,
    value: *mut T,
    nvalues: usize,
    conv: fn(f64) -> T,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let (Some(vrs), Some(out)) = (slice(vr, nvr), slice_mut(value, nvalues)) else {
                return null_arg(comp, function, "valueReferences or values");
            };
            if nvalues != nvr {
                let m = format!("nValues = {nvalues} for {nvr} scalar value references");
                return comp.fail(FmiError {
                    function,
                    message: m,
                });
            }
            for (o, &r) in out.iter_mut().zip(vrs) {
                let mut x = [comp.instance.time_s];
                if !(kind == Kind::Real && r == TIME_VR) {
                    if let Err(e) = comp.instance.get(function, kind, &[r], &mut x) {
                        let m = format!("{}: {}", fmi3_name(e.function), e.message);
                        comp.log(ERROR, "logStatusError", &m);
                        return ERROR;
                    }
                }
                *o = conv(x[0]);
            }
            OK
        })
    }
}

unsafe fn set_values<T: Copy>(
    instance: fmi3Instance,
    function: &'static str,
    kind: Kind,
    vr: *const fmi3ValueReference,
    nvr: usize,
    value: *const T,
    nvalues: usize,
    conv: fn(T) -> f64,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let (Some(vrs), Some(vals)) = (slice(vr, nvr), slice(value, nvalues)) else {
                return null_arg(comp, function, "valueReferences or values");
            };
            if nvalues != nvr {
                let m = format!("nValues = {nvalues} for {nvr} scalar value references");
                return comp.fail(FmiError {
                    function,
                    message: m,
                });
            }
            let v: Vec<f64> = vals.iter().map(|x| conv(*x)).collect();
            let r = comp.instance.set(function, kind, vrs, &v);
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        get_values(
            instance,
            "fmi2GetReal",
            Kind::Real,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |x| x,
        )
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        set_values(
            instance,
            "fmi2SetReal",
            Kind::Real,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |x| x,
        )
    }
}

/// Enumerations travel as Int64 in FMI 3.0.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int64,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        get_values(
            instance,
            "fmi2GetInteger",
            Kind::Integer,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |x| x as i64,
        )
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int64,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        set_values(
            instance,
            "fmi2SetInteger",
            Kind::Integer,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |x| x as f64,
        )
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        get_values(
            instance,
            "fmi3GetBoolean",
            Kind::Boolean,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |x| x != 0.0,
        )
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    unsafe {
        set_values(
            instance,
            "fmi3SetBoolean",
            Kind::Boolean,
            valueReferences,
            nValueReferences,
            values,
            nValues,
            |x| if x { 1.0 } else { 0.0 },
        )
    }
}
