//! The FMI 2.0 Co-Simulation C ABI over [`Instance`]: every function a CS FMU must export,
//! with the exact `fmi-sys` signatures (checked at compile time below). Each body runs
//! under `catch_unwind`: no panic crosses the boundary. Errors are logged through the
//! importer's logger with the function name and the reason, and return fmi2Error.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use super::instance::{deserialize, serialize, FmiError, Instance, Phase, Snapshot};
use super::model_description::GUID;
use super::variables::Kind;
use crate::params::Params;
use fmi_sys::fmi2::*;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

const OK: fmi2Status = fmi2Status_fmi2OK;
const DISCARD: fmi2Status = fmi2Status_fmi2Discard;
const ERROR: fmi2Status = fmi2Status_fmi2Error;
const FATAL: fmi2Status = fmi2Status_fmi2Fatal;

/// The C-side component: the instance plus the importer's callbacks.
struct Component {
    instance: Instance,
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

    fn result(&mut self, r: Result<(), FmiError>) -> fmi2Status {
        match r {
            Ok(()) => OK,
            Err(e) => self.fail(e),
        }
    }
}

/// Run `f` on the component, turning a null component and any panic into fmi2Error/Fatal.
unsafe fn with(c: fmi2Component, f: impl FnOnce(&mut Component) -> fmi2Status) -> fmi2Status {
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
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: the importer promises n elements at p.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: as above.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

fn null_arg(comp: &mut Component, function: &'static str, what: &str) -> fmi2Status {
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

/// `file:///path/resources` (or a plain path) to a path.
fn resource_path(uri: &str) -> std::path::PathBuf {
    let p = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
        .unwrap_or(uri);
    let p = if p.starts_with("//") { &p[1..] } else { p };
    // minimal percent-decoding (spaces and the like)
    let mut out = Vec::new();
    let b = p.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(x) = u8::from_str_radix(&p[i + 1..i + 3], 16) {
                out.push(x);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    std::path::PathBuf::from(String::from_utf8_lossy(&out).into_owned())
}

/// Start parameters: resources/parameters.toml when the FMU carries one, else the defaults.
fn start_params(resources: Option<&str>) -> Result<Params, String> {
    let Some(uri) = resources else {
        return Ok(Params::trees_lab());
    };
    let path = resource_path(uri).join("parameters.toml");
    if path.exists() {
        Params::from_file(&path).map_err(|e| e.to_string())
    } else {
        Ok(Params::trees_lab())
    }
}

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
    let r = catch_unwind(AssertUnwindSafe(|| {
        if functions.is_null() {
            return std::ptr::null_mut();
        }
        // SAFETY: non-null callbacks struct from the importer.
        let cb = unsafe { *functions };
        let name = unsafe { c_str(instanceName) };
        let mut comp = Component {
            instance: Instance::new(name.as_deref().unwrap_or(""), Params::trees_lab()),
            logger: cb.logger,
            environment: cb.componentEnvironment,
            name: CString::new(name.clone().unwrap_or_default()).unwrap_or_default(),
        };
        let refuse = |comp: &Component, m: String| {
            comp.log(ERROR, "logStatusError", &format!("fmi2Instantiate: {m}"));
            std::ptr::null_mut()
        };
        if name.as_deref().map(str::is_empty).unwrap_or(true) {
            return refuse(&comp, "instanceName is null or empty".into());
        }
        if fmuType != fmi2Type_fmi2CoSimulation {
            return refuse(
                &comp,
                format!("fmuType {fmuType}: this FMU is Co-Simulation only"),
            );
        }
        match unsafe { c_str(fmuGUID) } {
            Some(g) if g == GUID => {}
            g => {
                return refuse(
                    &comp,
                    format!("GUID {g:?} does not match this binary's {GUID}"),
                )
            }
        }
        let res = unsafe { c_str(fmuResourceLocation) };
        match start_params(res.as_deref()) {
            Ok(p) => comp.instance = Instance::new(&comp.instance.name, p),
            Err(e) => return refuse(&comp, format!("resources/parameters.toml: {e}")),
        }
        comp.instance.logging_on = loggingOn != 0;
        Box::into_raw(Box::new(comp)) as fmi2Component
    }));
    r.unwrap_or(std::ptr::null_mut())
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
        with(c, |comp| {
            let r = comp.instance.exit_initialization_mode();
            comp.result(r)
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
