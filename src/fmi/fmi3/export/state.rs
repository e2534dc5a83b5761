//! The FMU state: get, set, free, and its serialisation to bytes.

#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use super::*;
use crate::fmi::export::slice;
use crate::fmi::instance::{deserialize, serialize, FmiError, Snapshot};
use fmi_sys::fmi3::*;

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            if FMUState.is_null() {
                return null_arg(comp, "fmi3GetFMUState", "FMUState");
            }
            if !(*FMUState).is_null() {
                drop(Box::from_raw(*FMUState as *mut Snapshot));
            }
            *FMUState = Box::into_raw(Box::new(comp.instance.snapshot())) as fmi3FMUState;
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            if FMUState.is_null() {
                return null_arg(comp, "fmi3SetFMUState", "FMUState");
            }
            let snap = (*(FMUState as *const Snapshot)).clone();
            let r = comp.instance.restore(&snap);
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    unsafe {
        with(instance, |_| {
            if !FMUState.is_null() && !(*FMUState).is_null() {
                drop(Box::from_raw(*FMUState as *mut Snapshot));
                *FMUState = std::ptr::null_mut();
            }
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            if FMUState.is_null() || size.is_null() {
                return null_arg(comp, "fmi3SerializedFMUStateSize", "FMUState or size");
            }
            *size = serialize(&*(FMUState as *const Snapshot)).len();
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    serializedState: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            if FMUState.is_null() || serializedState.is_null() {
                return null_arg(comp, "fmi3SerializeFMUState", "FMUState or serializedState");
            }
            let bytes = serialize(&*(FMUState as *const Snapshot));
            if bytes.len() != size {
                let m = format!("size {size}, the state needs {}", bytes.len());
                return comp.fail(FmiError {
                    function: "fmi3SerializeFMUState",
                    message: m,
                });
            }
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), serializedState, size);
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serializedState: *const fmi3Byte,
    size: usize,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let (Some(bytes), false) = (slice(serializedState, size), FMUState.is_null()) else {
                return null_arg(
                    comp,
                    "fmi3DeserializeFMUState",
                    "serializedState or FMUState",
                );
            };
            match deserialize(bytes) {
                Ok(s) => {
                    *FMUState = Box::into_raw(Box::new(s)) as fmi3FMUState;
                    OK
                }
                Err(m) => comp.fail(FmiError {
                    function: "fmi3DeserializeFMUState",
                    message: m,
                }),
            }
        })
    }
}
