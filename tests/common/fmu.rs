//! The FMU driven through its C ABI in-process, for the FMU tests: instantiation with
//! raw resource-location bytes, the calls the tests repeat, the messages the instance
//! logged (fmi-sys' logger forwards to `log`) and the test threads that panicked (any
//! panic, even one caught at the boundary, is a defect).

use fmi_sys::fmi2::*;
use shaketable::fmi::export::*;
use shaketable::fmi::model_description::guid;
use std::ffi::CString;
use std::sync::{Mutex, Once};

pub static LOGGED: Mutex<Vec<(String, String)>> = Mutex::new(Vec::new());
/// Names of the threads that panicked (a test thread's name is the test's).
pub static PANICKED: Mutex<Vec<String>> = Mutex::new(Vec::new());
struct Collect;
impl log::Log for Collect {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }
    fn log(&self, r: &log::Record) {
        LOGGED
            .lock()
            .unwrap()
            .push((r.target().to_string(), r.args().to_string()));
    }
    fn flush(&self) {}
}
static INIT: Once = Once::new();

pub fn setup() {
    INIT.call_once(|| {
        let _ = log::set_logger(&Collect);
        log::set_max_level(log::LevelFilter::Trace);
        // any panic, even one caught at the boundary, is a defect
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let name = std::thread::current().name().unwrap_or("").to_string();
            if let Ok(mut p) = PANICKED.lock() {
                p.push(name);
            }
            default(info)
        }));
    });
}

pub fn logged(instance: &str) -> Vec<String> {
    LOGGED
        .lock()
        .unwrap()
        .iter()
        .filter(|(t, _)| t == instance)
        .map(|(_, m)| m.clone())
        .collect()
}

pub struct Fmu {
    pub c: fmi2Component,
    _name: CString,
    _cb: Box<fmi2CallbackFunctions>,
}

impl Fmu {
    /// Instantiate with `resources` as the raw location bytes (None: a null pointer) and
    /// the GUID of the TREES Lab defaults' description.
    pub fn open(name: &str, resources: Option<&[u8]>) -> Option<Fmu> {
        Fmu::open_as(name, resources, &guid(&shaketable::Params::trees_lab()))
    }

    /// Instantiate with the GUID `fmu_guid` (a description's, or a wrong one).
    pub fn open_as(name: &str, resources: Option<&[u8]>, fmu_guid: &str) -> Option<Fmu> {
        setup();
        let cb = Box::new(fmi2CallbackFunctions {
            logger: Some(fmi_sys::fmi2::logger::callback_logger_handler),
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: std::ptr::null_mut(),
        });
        let n = CString::new(name).unwrap();
        let guid = CString::new(fmu_guid).unwrap();
        let res = resources.map(|r| CString::new(r).unwrap());
        let c = unsafe {
            fmi2Instantiate(
                n.as_ptr(),
                fmi2Type_fmi2CoSimulation,
                guid.as_ptr(),
                res.as_ref().map_or(std::ptr::null(), |r| r.as_ptr()),
                &*cb,
                0,
                0,
            )
        };
        (!c.is_null()).then_some(Fmu {
            c,
            _name: n,
            _cb: cb,
        })
    }

    pub fn new(name: &str) -> Fmu {
        Fmu::open(name, None).expect("instantiate")
    }

    pub fn init_at(&self, t0: f64) {
        unsafe {
            assert_eq!(fmi2SetupExperiment(self.c, 0, 0.0, t0, 0, 0.0), 0);
            assert_eq!(fmi2EnterInitializationMode(self.c), 0);
            assert_eq!(fmi2ExitInitializationMode(self.c), 0);
        }
    }

    /// Set up, enter and leave initialisation at t = 0.
    pub fn init(&self) {
        self.init_at(0.0)
    }

    pub fn set(&self, vr: &[u32], v: &[f64]) -> fmi2Status {
        unsafe { fmi2SetReal(self.c, vr.as_ptr(), vr.len(), v.as_ptr()) }
    }

    pub fn slopes(&self, vr: &[u32], v: &[f64]) -> fmi2Status {
        let order = vec![1; vr.len()];
        unsafe {
            fmi2SetRealInputDerivatives(self.c, vr.as_ptr(), vr.len(), order.as_ptr(), v.as_ptr())
        }
    }

    pub fn get(&self, vr: &[u32]) -> Vec<f64> {
        let mut v = vec![0.0; vr.len()];
        assert_eq!(
            unsafe { fmi2GetReal(self.c, vr.as_ptr(), vr.len(), v.as_mut_ptr()) },
            0
        );
        v
    }

    pub fn step(&self, t: f64, h: f64) -> fmi2Status {
        unsafe { fmi2DoStep(self.c, t, h, 1) }
    }

    /// The current state serialised.
    pub fn state_bytes(&self) -> Vec<u8> {
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        let mut size = 0usize;
        unsafe {
            assert_eq!(fmi2GetFMUstate(self.c, &mut s), 0);
            assert_eq!(fmi2SerializedFMUstateSize(self.c, s, &mut size), 0);
            let mut bytes = vec![0 as fmi2Byte; size];
            assert_eq!(
                fmi2SerializeFMUstate(self.c, s, bytes.as_mut_ptr(), size),
                0
            );
            assert_eq!(fmi2FreeFMUstate(self.c, &mut s), 0);
            bytes.iter().map(|&b| b as u8).collect()
        }
    }

    /// Deserialise `bytes`; the status.
    pub fn load_state(&self, bytes: &[u8]) -> fmi2Status {
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        let st = unsafe {
            fmi2DeSerializeFMUstate(
                self.c,
                bytes.as_ptr() as *const fmi2Byte,
                bytes.len(),
                &mut s,
            )
        };
        if !s.is_null() {
            unsafe { fmi2FreeFMUstate(self.c, &mut s) };
        }
        st
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}
