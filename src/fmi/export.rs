//! The FMI 2.0 Co-Simulation C ABI over [`Instance`]: every function a CS FMU must export,
//! with the exact `fmi-sys` signatures (checked at compile time below). Each body runs
//! under `catch_unwind`: no panic crosses the boundary. Errors are logged through the
//! importer's logger with the function name and the reason, and return fmi2Error.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use super::instance::{
    deserialize, fmi_name_of_key, serialize, FmiError, Instance, Interface, Phase, Snapshot,
};
use super::model_description::guid as description_guid;
use super::variables::Kind;
use crate::params::{Params, ParamsError};
use fmi_sys::fmi2::*;
use std::ffi::{c_char, CStr, CString};
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

/// The largest parameters.toml read: a real one is a few kB; anything larger is not a
/// parameter file (and a device such as /dev/zero would never end).
const MAX_PARAMETERS_FILE_BYTES: u64 = 1 << 20;

/// Why a resource location cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ResourceUriError {
    #[error("is empty")]
    Empty,
    #[error("is not a file URI (expected file:///path, file://localhost/path or file:/path)")]
    NotFile,
    #[error(
        "names the host {0:?}: only local files (file:///path, file://localhost/path) can be read"
    )]
    RemoteHost(String),
    #[error("has a bad percent escape at byte {0} (expected % and two hex digits)")]
    BadEscape(usize),
    #[error("decodes to a path with a NUL byte")]
    Nul,
}

/// `file:///p`, `file://localhost/p`, `file:/p` (RFC 8089; the scheme in any case) or a
/// plain absolute path, percent-decoded on bytes, to a local path.
pub fn resource_path(uri: &[u8]) -> Result<std::path::PathBuf, ResourceUriError> {
    use ResourceUriError::*;
    if uri.is_empty() {
        return Err(Empty);
    }
    let encoded: &[u8] = if uri.len() >= 5 && uri[..5].eq_ignore_ascii_case(b"file:") {
        let rest = &uri[5..];
        match rest.strip_prefix(b"//") {
            Some(auth) => {
                let end = auth.iter().position(|&b| b == b'/').unwrap_or(auth.len());
                let host = &auth[..end];
                if !(host.is_empty() || host.eq_ignore_ascii_case(b"localhost")) {
                    return Err(RemoteHost(String::from_utf8_lossy(host).into_owned()));
                }
                &auth[end..]
            }
            None if rest.starts_with(b"/") => rest,
            None => return Err(NotFile),
        }
    } else if uri.starts_with(b"/") {
        uri
    } else {
        return Err(NotFile);
    };
    let path = percent_decode(encoded)?;
    if path.contains(&0) {
        return Err(Nul);
    }
    Ok(path_from_bytes(path))
}

/// `%XX` to the byte XX; a `%` without two hex digits is an error.
fn percent_decode(b: &[u8]) -> Result<Vec<u8>, ResourceUriError> {
    let hex = |c: u8| (c as char).to_digit(16).map(|d| d as u8);
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let (Some(h), Some(l)) = (
                b.get(i + 1).copied().and_then(hex),
                b.get(i + 2).copied().and_then(hex),
            ) else {
                return Err(ResourceUriError::BadEscape(i));
            };
            out.push(h << 4 | l);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    Ok(out)
}

#[cfg(unix)]
fn path_from_bytes(b: Vec<u8>) -> std::path::PathBuf {
    use std::os::unix::ffi::OsStringExt;
    std::ffi::OsString::from_vec(b).into()
}

#[cfg(not(unix))]
fn path_from_bytes(b: Vec<u8>) -> std::path::PathBuf {
    String::from_utf8_lossy(&b).into_owned().into()
}

/// Start parameters and, when they are the defaults for want of a usable location, the
/// warning that says so.
///
/// What a user expects: an FMU built with `--params` runs the lab's values or refuses to
/// start, never the defaults behind their back. So a location that exists with a
/// parameters.toml that cannot be read or is invalid is an error; a folder without one
/// is an FMU built without `--params` (defaults, silently); a null, malformed or missing
/// location means the importer lost the FMU's resources: the defaults run, with a
/// warning that names the location and says so.
pub fn start_params(resources: Option<&[u8]>) -> Result<(Params, Option<String>), String> {
    const DEFAULTS: &str = "the built-in TREES Lab defaults are used \
        (a resources/parameters.toml shipped in the FMU cannot be read)";
    let Some(uri) = resources else {
        return Ok((
            Params::trees_lab(),
            Some(format!("fmuResourceLocation is null: {DEFAULTS}")),
        ));
    };
    let shown = String::from_utf8_lossy(uri);
    let dir = match resource_path(uri) {
        Ok(d) => d,
        Err(e) => {
            let w = format!("fmuResourceLocation {shown:?} {e}: {DEFAULTS}");
            return Ok((Params::trees_lab(), Some(w)));
        }
    };
    if !dir.is_dir() {
        let w = format!(
            "fmuResourceLocation {shown:?} is not a folder ({}): {DEFAULTS}",
            dir.display()
        );
        return Ok((Params::trees_lab(), Some(w)));
    }
    let path = dir.join("parameters.toml");
    match std::fs::symlink_metadata(&path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok((Params::trees_lab(), None)),
        Err(e) => Err(format!("{}: {e}", path.display())),
        Ok(_) => read_parameters(&path).map(|p| (p, None)),
    }
}

/// A parameters.toml that exists: a regular file of plausible size, valid.
fn read_parameters(path: &std::path::Path) -> Result<Params, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if !meta.is_file() {
        return Err(format!("{}: not a regular file", path.display()));
    }
    if meta.len() > MAX_PARAMETERS_FILE_BYTES {
        return Err(format!(
            "{}: {} bytes, larger than any parameter file ({MAX_PARAMETERS_FILE_BYTES} bytes at most)",
            path.display(),
            meta.len()
        ));
    }
    Params::from_file(path).map_err(|e| match &e {
        // the file's own key, and the FMI variable it sets
        ParamsError::Invalid { key, .. } => match fmi_name_of_key(key) {
            Some(name) => format!("{e} (FMI variable {name})"),
            None => e.to_string(),
        },
        _ => e.to_string(),
    })
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
        with(c, |comp| {
            let r = comp.instance.exit_initialization_mode();
            let status = comp.result(r);
            // spec section 8: an unstable closed loop is named before the first step
            match crate::linear::stability_warning(&comp.instance.params) {
                Some(w) if status == OK => {
                    let message = format!("fmi2ExitInitializationMode: {w}");
                    comp.log(WARNING, "logStatusWarning", &message);
                    WARNING
                }
                _ => status,
            }
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn resource_uris_are_parsed_on_bytes() {
        let p = |u: &[u8]| resource_path(u);
        let ok = |s: &str| Ok(PathBuf::from(s));
        assert_eq!(p(b"file:///a/b%20c"), ok("/a/b c"));
        assert_eq!(p(b"file://localhost/a/b"), ok("/a/b"));
        assert_eq!(p(b"FILE://LOCALHOST/a"), ok("/a"));
        assert_eq!(p(b"file:/a/%C3%A9"), ok("/a/\u{e9}"));
        assert_eq!(p(b"/plain/path"), ok("/plain/path"));
        use ResourceUriError::*;
        assert_eq!(p(b"file:///a%\xc3\xa9"), Err(BadEscape(2)));
        assert_eq!(p(b"file:///a%4"), Err(BadEscape(2)));
        assert_eq!(p(b"file:///a%00b"), Err(Nul));
        assert_eq!(p(b"file://server/a"), Err(RemoteHost("server".into())));
        assert_eq!(p(b"file:a"), Err(NotFile));
        assert_eq!(p(b"http://x/a"), Err(NotFile));
        assert_eq!(p(b""), Err(Empty));
    }
}
