//! The FMI 3.0 Co-Simulation C ABI over [`Instance`], in the same shared library as the
//! FMI 2.0 functions (their names differ): every function of `fmi3FunctionTypes.h` is
//! exported with the exact `fmi-sys` signature (checked at compile time at the end), so
//! any importer can load the binary. Model Exchange, Scheduled Execution, clocks, event
//! mode and derivatives are refused with a logged message. No panic crosses the boundary.

#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use super::model_description::{instantiation_token, TIME_VR};
use crate::fmi::export::{slice, slice_mut, start_params};
use crate::fmi::instance::{deserialize, serialize, FmiError, Instance, Phase, Snapshot};
use crate::fmi::variables::Kind;
use fmi_sys::fmi3::*;
use std::ffi::{c_char, CStr, CString};
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

#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    loggingOn: fmi3Boolean,
    _nCategories: usize,
    _categories: *const fmi3String,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            comp.instance.logging_on = loggingOn;
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    _earlyReturnAllowed: fmi3Boolean,
    _requiredIntermediateVariables: *const fmi3ValueReference,
    _nRequiredIntermediateVariables: usize,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    _intermediateUpdate: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    let name = unsafe { c_str(instanceName) }.unwrap_or_default();
    let mut comp = Component {
        instance: Instance::new(&name, crate::Params::trees_lab()),
        logger: logMessage,
        environment: instanceEnvironment,
    };
    let token = unsafe { c_str(instantiationToken) };
    let resources = (!resourcePath.is_null())
        // SAFETY: a NUL-terminated path from the importer.
        .then(|| unsafe { CStr::from_ptr(resourcePath) }.to_bytes());
    let r = catch_unwind(AssertUnwindSafe(|| {
        instantiate(&mut comp, token.as_deref(), eventModeUsed, resources)
    }));
    match r {
        Ok(Ok(())) => {
            comp.instance.logging_on = loggingOn;
            Box::into_raw(Box::new(comp)) as fmi3Instance
        }
        Ok(Err(m)) => {
            comp.log(
                ERROR,
                "logStatusError",
                &format!("fmi3InstantiateCoSimulation: {m}"),
            );
            std::ptr::null_mut()
        }
        Err(_) => std::ptr::null_mut(),
    }
}

/// The checks of fmi3InstantiateCoSimulation; `Err` is the refusal's reason.
fn instantiate(
    comp: &mut Component,
    token: Option<&str>,
    event_mode_used: bool,
    resources: Option<&[u8]>,
) -> Result<(), String> {
    if comp.instance.name.is_empty() {
        return Err("instanceName is null or empty".into());
    }
    if event_mode_used {
        return Err("eventModeUsed: this FMU has no event mode (hasEventMode = false)".into());
    }
    let (params, warning) =
        start_params(resources).map_err(|e| format!("resources/parameters.toml: {e}"))?;
    if let Some(w) = warning {
        let w = w.replace("fmuResourceLocation", "resourcePath");
        comp.log(
            WARNING,
            "logStatusWarning",
            &format!("fmi3InstantiateCoSimulation: {w}"),
        );
    }
    let expected = instantiation_token(&params);
    if token != Some(expected.as_str()) {
        return Err(format!(
            "instantiationToken {token:?} does not match {expected}, the token of the \
             modelDescription.xml this binary generates for its start values: the FMU's \
             files do not belong together"
        ));
    }
    comp.instance = Instance::new(&comp.instance.name, params);
    Ok(())
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    _instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
) -> fmi3Instance {
    let comp = Component {
        instance: Instance::new("", crate::Params::trees_lab()),
        logger: logMessage,
        environment: instanceEnvironment,
    };
    comp.log(
        ERROR,
        "logStatusError",
        &format!("fmi3InstantiateModelExchange: {CO_SIMULATION_ONLY}"),
    );
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    _clockUpdate: fmi3ClockUpdateCallback,
    _lockPreemption: fmi3LockPreemptionCallback,
    _unlockPreemption: fmi3UnlockPreemptionCallback,
) -> fmi3Instance {
    let comp = Component {
        instance: Instance::new("", crate::Params::trees_lab()),
        logger: logMessage,
        environment: instanceEnvironment,
    };
    let m = format!("fmi3InstantiateScheduledExecution: {CO_SIMULATION_ONLY}");
    comp.log(ERROR, "logStatusError", &m);
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    if !instance.is_null() {
        // SAFETY: the Box made by fmi3InstantiateCoSimulation, freed once.
        let _ = catch_unwind(AssertUnwindSafe(|| unsafe {
            drop(Box::from_raw(instance as *mut Component))
        }));
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    _toleranceDefined: fmi3Boolean,
    _tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let stop = stopTimeDefined.then_some(stopTime);
            let r = comp
                .instance
                .setup_experiment(startTime, stop)
                .and_then(|_| comp.instance.enter_initialization_mode());
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let r = comp.instance.exit_initialization_mode();
            let status = comp.result(r);
            match crate::linear::stability_warning(&comp.instance.params) {
                Some(w) if status == OK => {
                    comp.log(
                        WARNING,
                        "logStatusWarning",
                        &format!("fmi3ExitInitializationMode: {w}"),
                    );
                    WARNING
                }
                _ => status,
            }
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let r = comp.instance.terminate();
            comp.result(r)
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            comp.instance.reset();
            OK
        })
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    unsafe {
        with(instance, |comp| {
            let r = comp
                .instance
                .do_step(currentCommunicationPoint, communicationStepSize);
            let status = comp.result(r);
            let put = |p: *mut bool, v: bool| {
                if !p.is_null() {
                    *p = v;
                }
            };
            put(eventHandlingNeeded, false);
            put(terminateSimulation, status != OK);
            put(earlyReturn, false);
            if !lastSuccessfulTime.is_null() {
                *lastSuccessfulTime = comp.instance.time_s;
            }
            status
        })
    }
}

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

/// Functions this FMU does not offer, each with its exact signature (checked against
/// the `fmi-sys` type): logged and refused with fmi3Error.
macro_rules! not_offered {
    ($($name:ident, $ty:ident ( $($arg:ident : $t:ty),* );)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $name(instance: fmi3Instance, $($arg: $t),*) -> fmi3Status {
            $(let _ = $arg;)*
            unsafe { refuse(instance, stringify!($name), CO_SIMULATION_ONLY) }
        }
        const _: $ty = Some($name);
    )*};
}

not_offered! {
    fmi3GetFloat32, fmi3GetFloat32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Float32, nValues: usize);
    fmi3GetInt8, fmi3GetInt8TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Int8, nValues: usize);
    fmi3GetUInt8, fmi3GetUInt8TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3UInt8, nValues: usize);
    fmi3GetInt16, fmi3GetInt16TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Int16, nValues: usize);
    fmi3GetUInt16, fmi3GetUInt16TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3UInt16, nValues: usize);
    fmi3GetInt32, fmi3GetInt32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Int32, nValues: usize);
    fmi3GetUInt32, fmi3GetUInt32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3UInt32, nValues: usize);
    fmi3GetUInt64, fmi3GetUInt64TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3UInt64, nValues: usize);
    fmi3GetString, fmi3GetStringTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3String, nValues: usize);
    fmi3GetBinary, fmi3GetBinaryTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, valueSizes: *mut usize, values: *mut fmi3Binary, nValues: usize);
    fmi3GetClock, fmi3GetClockTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Clock);
    fmi3SetFloat32, fmi3SetFloat32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Float32, nValues: usize);
    fmi3SetInt8, fmi3SetInt8TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Int8, nValues: usize);
    fmi3SetUInt8, fmi3SetUInt8TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3UInt8, nValues: usize);
    fmi3SetInt16, fmi3SetInt16TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Int16, nValues: usize);
    fmi3SetUInt16, fmi3SetUInt16TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3UInt16, nValues: usize);
    fmi3SetInt32, fmi3SetInt32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Int32, nValues: usize);
    fmi3SetUInt32, fmi3SetUInt32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3UInt32, nValues: usize);
    fmi3SetUInt64, fmi3SetUInt64TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3UInt64, nValues: usize);
    fmi3SetString, fmi3SetStringTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3String, nValues: usize);
    fmi3SetBinary, fmi3SetBinaryTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, valueSizes: *const usize, values: *const fmi3Binary, nValues: usize);
    fmi3SetClock, fmi3SetClockTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Clock);
    fmi3GetNumberOfVariableDependencies, fmi3GetNumberOfVariableDependenciesTYPE (valueReference: fmi3ValueReference, nDependencies: *mut usize);
    fmi3GetVariableDependencies, fmi3GetVariableDependenciesTYPE (dependent: fmi3ValueReference, elementIndicesOfDependent: *mut usize, independents: *mut fmi3ValueReference, elementIndicesOfIndependents: *mut usize, dependencyKinds: *mut fmi3DependencyKind, nDependencies: usize);
    fmi3GetDirectionalDerivative, fmi3GetDirectionalDerivativeTYPE (unknowns: *const fmi3ValueReference, nUnknowns: usize, knowns: *const fmi3ValueReference, nKnowns: usize, seed: *const fmi3Float64, nSeed: usize, sensitivity: *mut fmi3Float64, nSensitivity: usize);
    fmi3GetAdjointDerivative, fmi3GetAdjointDerivativeTYPE (unknowns: *const fmi3ValueReference, nUnknowns: usize, knowns: *const fmi3ValueReference, nKnowns: usize, seed: *const fmi3Float64, nSeed: usize, sensitivity: *mut fmi3Float64, nSensitivity: usize);
    fmi3EnterConfigurationMode, fmi3EnterConfigurationModeTYPE ();
    fmi3ExitConfigurationMode, fmi3ExitConfigurationModeTYPE ();
    fmi3GetIntervalDecimal, fmi3GetIntervalDecimalTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, intervals: *mut fmi3Float64, qualifiers: *mut fmi3IntervalQualifier);
    fmi3GetIntervalFraction, fmi3GetIntervalFractionTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64, qualifiers: *mut fmi3IntervalQualifier);
    fmi3GetShiftDecimal, fmi3GetShiftDecimalTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, shifts: *mut fmi3Float64);
    fmi3GetShiftFraction, fmi3GetShiftFractionTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64);
    fmi3SetIntervalDecimal, fmi3SetIntervalDecimalTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, intervals: *const fmi3Float64);
    fmi3SetIntervalFraction, fmi3SetIntervalFractionTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64);
    fmi3SetShiftDecimal, fmi3SetShiftDecimalTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, shifts: *const fmi3Float64);
    fmi3SetShiftFraction, fmi3SetShiftFractionTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64);
    fmi3EvaluateDiscreteStates, fmi3EvaluateDiscreteStatesTYPE ();
    fmi3UpdateDiscreteStates, fmi3UpdateDiscreteStatesTYPE (discreteStatesNeedUpdate: *mut fmi3Boolean, terminateSimulation: *mut fmi3Boolean, nominalsOfContinuousStatesChanged: *mut fmi3Boolean, valuesOfContinuousStatesChanged: *mut fmi3Boolean, nextEventTimeDefined: *mut fmi3Boolean, nextEventTime: *mut fmi3Float64);
    fmi3EnterEventMode, fmi3EnterEventModeTYPE ();
    fmi3EnterContinuousTimeMode, fmi3EnterContinuousTimeModeTYPE ();
    fmi3CompletedIntegratorStep, fmi3CompletedIntegratorStepTYPE (noSetFMUStatePriorToCurrentPoint: fmi3Boolean, enterEventMode: *mut fmi3Boolean, terminateSimulation: *mut fmi3Boolean);
    fmi3SetTime, fmi3SetTimeTYPE (time: fmi3Float64);
    fmi3SetContinuousStates, fmi3SetContinuousStatesTYPE (continuousStates: *const fmi3Float64, nContinuousStates: usize);
    fmi3GetContinuousStateDerivatives, fmi3GetContinuousStateDerivativesTYPE (derivatives: *mut fmi3Float64, nContinuousStates: usize);
    fmi3GetEventIndicators, fmi3GetEventIndicatorsTYPE (eventIndicators: *mut fmi3Float64, nEventIndicators: usize);
    fmi3GetContinuousStates, fmi3GetContinuousStatesTYPE (continuousStates: *mut fmi3Float64, nContinuousStates: usize);
    fmi3GetNominalsOfContinuousStates, fmi3GetNominalsOfContinuousStatesTYPE (nominals: *mut fmi3Float64, nContinuousStates: usize);
    fmi3GetNumberOfEventIndicators, fmi3GetNumberOfEventIndicatorsTYPE (nEventIndicators: *mut usize);
    fmi3GetNumberOfContinuousStates, fmi3GetNumberOfContinuousStatesTYPE (nContinuousStates: *mut usize);
    fmi3EnterStepMode, fmi3EnterStepModeTYPE ();
    fmi3GetOutputDerivatives, fmi3GetOutputDerivativesTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, orders: *const fmi3Int32, values: *mut fmi3Float64, nValues: usize);
    fmi3ActivateModelPartition, fmi3ActivateModelPartitionTYPE (clockReference: fmi3ValueReference, activationTime: fmi3Float64);
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
