//! The FMU state: get, set, free, and its serialisation to bytes.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use super::*;
use crate::fmi::instance::{deserialize, serialize, FmiError, Snapshot};
use fmi_sys::fmi2::*;
use std::ffi::c_char;

#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if FMUstate.is_null() {
                return null_arg(comp, "fmi2GetFMUstate", "FMUstate");
            }
            let snap = Box::new(comp.instance.snapshot());
            // SAFETY: FMUstate is non-null. An existing state is overwritten in place.
            let slot = &mut *FMUstate;
            if slot.is_null() {
                *slot = Box::into_raw(snap) as fmi2FMUstate;
            } else {
                *(*slot as *mut Snapshot) = *snap;
            }
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if FMUstate.is_null() {
                return null_arg(comp, "fmi2SetFMUstate", "FMUstate");
            }
            // SAFETY: a state from fmi2GetFMUstate or fmi2DeSerializeFMUstate.
            let snap = (*(FMUstate as *const Snapshot)).clone();
            let r = comp.instance.restore(&snap);
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if FMUstate.is_null() {
                return null_arg(comp, "fmi2FreeFMUstate", "FMUstate");
            }
            let slot = &mut *FMUstate;
            if !slot.is_null() {
                drop(Box::from_raw(*slot as *mut Snapshot));
                *slot = std::ptr::null_mut();
            }
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if FMUstate.is_null() || size.is_null() {
                return null_arg(comp, "fmi2SerializedFMUstateSize", "FMUstate or size");
            }
            *size = serialize(&*(FMUstate as *const Snapshot)).len();
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            if FMUstate.is_null() || serializedState.is_null() {
                return null_arg(comp, "fmi2SerializeFMUstate", "FMUstate or serializedState");
            }
            let bytes = serialize(&*(FMUstate as *const Snapshot));
            if size < bytes.len() {
                return comp.fail(FmiError {
                    function: "fmi2SerializeFMUstate",
                    message: format!(
                        "buffer of {size} bytes, {} needed (fmi2SerializedFMUstateSize)",
                        bytes.len()
                    ),
                });
            }
            std::ptr::copy_nonoverlapping(
                bytes.as_ptr() as *const c_char,
                serializedState,
                bytes.len(),
            );
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        with(c, |comp| {
            let (Some(bytes), false) = (
                slice(serializedState as *const u8, size),
                FMUstate.is_null(),
            ) else {
                return null_arg(
                    comp,
                    "fmi2DeSerializeFMUstate",
                    "serializedState or FMUstate",
                );
            };
            match deserialize(bytes) {
                Ok(s) => {
                    let slot = &mut *FMUstate;
                    if !slot.is_null() {
                        drop(Box::from_raw(*slot as *mut Snapshot));
                    }
                    *slot = Box::into_raw(Box::new(s)) as fmi2FMUstate;
                    OK
                }
                Err(e) => comp.fail(FmiError {
                    function: "fmi2DeSerializeFMUstate",
                    message: e,
                }),
            }
        })
    }
}
