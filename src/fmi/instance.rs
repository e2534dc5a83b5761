//! One FMU instance as safe Rust: the FMI 2.0 Co-Simulation state machine with every call
//! checked against the state it is allowed in and against its arguments. The C exports
//! (`export.rs`) only translate pointers and log the errors returned here.

use super::variables::{by_vr, inputs_from, integer_allowed, Kind, Role, VARIABLES};
use crate::model::SensorNoise;
use crate::params::{Params, ParamsError};
use crate::solver::{CommandHistory, Simulator, DEFAULT_MAX_SUBSTEP_S};
use crate::Model;

/// FMI 2.0 states: Co-Simulation steps in `StepComplete`; Model Exchange alternates
/// `EventMode` and `ContinuousTimeMode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Phase {
    Instantiated,
    InitializationMode,
    StepComplete,
    EventMode,
    ContinuousTimeMode,
    Terminated,
    Error,
}

/// The phases after initialization in which a simulation runs (either interface).
pub const RUNNING: [Phase; 3] = [
    Phase::StepComplete,
    Phase::EventMode,
    Phase::ContinuousTimeMode,
];

/// Which FMI interface the importer instantiated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interface {
    #[default]
    CoSimulation,
    ModelExchange,
}

/// A refused call: the FMI function and what was wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct FmiError {
    pub function: &'static str,
    pub message: String,
}

impl std::fmt::Display for FmiError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.function, self.message)
    }
}

type Result<T> = std::result::Result<T, FmiError>;

/// Accepted mismatch of `currentCommunicationPoint`, in units of the rounding error of the
/// current time: an importer that accumulates `t += h` over millions of steps drifts by a
/// few thousand ulps, while any real mismatch (a skipped or repeated step) is far larger.
const COMM_POINT_ULPS: f64 = 4096.0;

/// ... but never more than this fraction of the step: at t = 1e9 s the ulp allowance
/// (1e-3 s) would otherwise accept a jump of a millisecond step.
const COMM_POINT_STEP_FRACTION: f64 = 1e-3;

/// A step whose representable end time `t + h` misses `h` by more than this fraction
/// is refused: time cannot resolve the step there (at t = 1e20 s, `t + h == t`). Below
/// it the rounding of the end time is the usual drift of a double time axis (at
/// t = 1e9 s a 1 ms step is off by 1e-4 of itself).
const TIME_RESOLUTION_FRACTION: f64 = 0.01;

/// Largest accepted `|currentCommunicationPoint - time|` for a step of `h` at `time`.
fn comm_point_tolerance(time: f64, h: f64) -> f64 {
    (COMM_POINT_ULPS * f64::EPSILON * time.abs().max(1.0)).min(COMM_POINT_STEP_FRACTION * h)
}

/// The FMI variable name of a parameter-file key (`table.mass_kg` -> `table.mass`);
/// `None` for a key with no variable.
pub fn fmi_name_of_key(key: &str) -> Option<&'static str> {
    VARIABLES
        .iter()
        .find(|v| v.key == Some(key))
        .map(|v| v.name)
}

/// A parameter error in the FMU's words: the FMI variable name, not the TOML key.
pub fn params_message(e: &ParamsError) -> String {
    match e {
        ParamsError::Invalid {
            key, value, rule, ..
        } => {
            let name = fmi_name_of_key(key).unwrap_or(key);
            format!("{name} = {value}: {rule}")
        }
        other => other.to_string(),
    }
}

/// Everything an FMU state snapshot holds (get/set/serialize FMUstate).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Snapshot {
    pub phase: Phase,
    pub params: Params,
    pub time_s: f64,
    pub start_time_s: f64,
    pub inputs: [f64; 4],
    pub input_slopes: [f64; 4],
    /// The simulator's state vector and command history (after initialization).
    pub state: Option<Vec<f64>>,
    pub history: Vec<(f64, f64)>,
}

impl Snapshot {
    /// Every number of a state must be finite: a NaN time or state would step on silently.
    pub fn check_finite(&self) -> std::result::Result<(), String> {
        let named: [(&str, &[f64]); 4] = [
            ("time", &[self.time_s, self.start_time_s]),
            ("input values", &self.inputs),
            ("input derivatives", &self.input_slopes),
            ("model state", self.state.as_deref().unwrap_or(&[])),
        ];
        for (what, xs) in named {
            if let Some(x) = xs.iter().find(|x| !x.is_finite()) {
                return Err(format!("the FMU state holds a non-finite {what} ({x})"));
            }
        }
        if self
            .history
            .iter()
            .any(|(t, u)| !(t.is_finite() && u.is_finite()))
        {
            return Err("the FMU state holds a non-finite valve command history".into());
        }
        Ok(())
    }
}

/// An FMU instance.
#[derive(Debug, Clone)]
pub struct Instance {
    pub name: String,
    /// Start values (defaults or the FMU's resources/parameters.toml); fmi2Reset returns here.
    pub start_params: Params,
    pub params: Params,
    pub phase: Phase,
    pub start_time_s: f64,
    pub time_s: f64,
    pub inputs: [f64; 4],
    pub input_slopes: [f64; 4],
    pub sim: Option<Simulator>,
    pub logging_on: bool,
    pub interface: Interface,
}

fn err<T>(function: &'static str, message: impl Into<String>) -> Result<T> {
    Err(FmiError {
        function,
        message: message.into(),
    })
}

impl Instance {
    pub fn new(name: &str, start_params: Params) -> Instance {
        Instance {
            name: name.to_string(),
            start_params,
            params: start_params,
            phase: Phase::Instantiated,
            start_time_s: 0.0,
            time_s: 0.0,
            inputs: [0.0; 4],
            input_slopes: [0.0; 4],
            sim: None,
            logging_on: false,
            interface: Interface::CoSimulation,
        }
    }

    fn allowed(&self, function: &'static str, phases: &[Phase]) -> Result<()> {
        if phases.contains(&self.phase) {
            Ok(())
        } else {
            err(
                function,
                format!(
                    "not allowed in state {:?} (allowed in {:?})",
                    self.phase, phases
                ),
            )
        }
    }

    pub fn setup_experiment(&mut self, start_s: f64, stop: Option<f64>) -> Result<()> {
        const F: &str = "fmi2SetupExperiment";
        self.allowed(F, &[Phase::Instantiated])?;
        if !start_s.is_finite() {
            return err(F, format!("startTime {start_s} is not finite"));
        }
        if let Some(t) = stop {
            if !(t.is_finite() && t >= start_s) {
                return err(F, format!("stopTime {t} is before startTime {start_s}"));
            }
        }
        self.start_time_s = start_s;
        self.time_s = start_s;
        Ok(())
    }

    pub fn enter_initialization_mode(&mut self) -> Result<()> {
        self.allowed("fmi2EnterInitializationMode", &[Phase::Instantiated])?;
        self.phase = Phase::InitializationMode;
        Ok(())
    }

    pub fn exit_initialization_mode(&mut self) -> Result<()> {
        const F: &str = "fmi2ExitInitializationMode";
        self.allowed(F, &[Phase::InitializationMode])?;
        if let Err(e) = self.params.validate() {
            return err(F, format!("invalid parameters: {}", params_message(&e)));
        }
        if self.interface == Interface::ModelExchange
            && self.params.servovalve.model == crate::params::ServovalveModel::Delay
        {
            return err(
                F,
                "servovalve.model = delay is not offered in Model Exchange: a pure delay \
                 needs the command's history, which an external integrator does not keep; \
                 use first_order or second_order, or the Co-Simulation interface",
            );
        }
        self.sim = Some(Simulator::new(
            Model::new(&self.params),
            self.start_time_s,
            DEFAULT_MAX_SUBSTEP_S,
        ));
        self.time_s = self.start_time_s;
        self.phase = match self.interface {
            Interface::CoSimulation => Phase::StepComplete,
            Interface::ModelExchange => Phase::EventMode,
        };
        Ok(())
    }

    pub fn terminate(&mut self) -> Result<()> {
        self.allowed("fmi2Terminate", &RUNNING)?;
        self.phase = Phase::Terminated;
        Ok(())
    }

    /// Back to the instantiated state with the start values.
    pub fn reset(&mut self) {
        let (name, logging, start) = (self.name.clone(), self.logging_on, self.start_params);
        let interface = self.interface;
        *self = Instance::new(&name, start);
        self.logging_on = logging;
        self.interface = interface;
    }

    /// The running simulation, or the table at rest before initialization is complete.
    pub(super) fn simulation(&self) -> std::borrow::Cow<'_, Simulator> {
        match &self.sim {
            Some(s) => std::borrow::Cow::Borrowed(s),
            None => std::borrow::Cow::Owned(Simulator::new(
                Model::new(&self.params),
                self.time_s,
                DEFAULT_MAX_SUBSTEP_S,
            )),
        }
    }

    /// Current readings (outputs at rest before initialization is complete).
    fn outputs(&self) -> crate::Outputs {
        let inp = inputs_from(&self.inputs);
        self.simulation().outputs(&inp, &SensorNoise::default())
    }

    fn variable(
        function: &'static str,
        vr: u32,
        kind: Kind,
    ) -> Result<&'static super::variables::Variable> {
        match by_vr(vr) {
            Some(v) if v.kind == kind => Ok(v),
            Some(v) => err(
                function,
                format!(
                    "value reference {vr} ({}) is a {:?}, not a {kind:?}",
                    v.name, v.kind
                ),
            ),
            None => err(function, format!("unknown value reference {vr}")),
        }
    }

    /// fmi2GetReal/Integer/Boolean as f64 values.
    pub fn get(
        &self,
        function: &'static str,
        kind: Kind,
        vrs: &[u32],
        out: &mut [f64],
    ) -> Result<()> {
        self.allowed(
            function,
            &[
                Phase::InitializationMode,
                Phase::StepComplete,
                Phase::EventMode,
                Phase::ContinuousTimeMode,
                Phase::Terminated,
                Phase::Error,
            ],
        )?;
        let needs =
            |f: fn(&Role) -> bool| vrs.iter().any(|&vr| by_vr(vr).is_some_and(|v| f(&v.role)));
        let o = needs(|r| matches!(r, Role::Output(_))).then(|| self.outputs());
        let sim =
            needs(|r| matches!(r, Role::State(_) | Role::Derivative(_))).then(|| self.simulation());
        let ds = needs(|r| matches!(r, Role::Derivative(_))).then(|| {
            let inp = inputs_from(&self.inputs);
            sim.as_ref().map(|s| s.derivatives_now(&inp))
        });
        for (i, &vr) in vrs.iter().enumerate() {
            let v = Self::variable(function, vr, kind)?;
            out[i] = match v.role {
                Role::Input(k) => self.inputs[k],
                Role::Output(f) => o.as_ref().map(f).unwrap_or(f64::NAN),
                Role::Parameter(get, _) => get(&self.params),
                Role::State(k) => sim.as_ref().map_or(f64::NAN, |s| s.state[k]),
                Role::Derivative(k) => ds.flatten().map_or(f64::NAN, |d| d[k]),
            };
        }
        Ok(())
    }

    /// fmi2SetReal/Integer/Boolean from f64 values; all-or-nothing.
    pub fn set(
        &mut self,
        function: &'static str,
        kind: Kind,
        vrs: &[u32],
        values: &[f64],
    ) -> Result<()> {
        self.allowed(
            function,
            &[
                Phase::Instantiated,
                Phase::InitializationMode,
                Phase::StepComplete,
                Phase::EventMode,
                Phase::ContinuousTimeMode,
            ],
        )?;
        let mut params = self.params;
        let mut inputs = self.inputs;
        let mut slopes = self.input_slopes;
        for (&vr, &x) in vrs.iter().zip(values) {
            let v = Self::variable(function, vr, kind)?;
            match v.role {
                Role::Input(k) => {
                    if !x.is_finite() {
                        return err(function, format!("input {} = {x} is not finite", v.name));
                    }
                    inputs[k] = x;
                    // FMI 2.0 (4.2.1): a new input value ends the derivative set for it
                    slopes[k] = 0.0;
                }
                Role::Output(_) => {
                    return err(
                        function,
                        format!("{} is an output and cannot be set", v.name),
                    )
                }
                Role::State(_) | Role::Derivative(_) => {
                    return err(
                        function,
                        format!(
                            "{} is a local variable of the model: states are set with \
                             fmi2SetContinuousStates (Model Exchange)",
                            v.name
                        ),
                    )
                }
                Role::Parameter(_, set) => {
                    if RUNNING.contains(&self.phase) {
                        return err(
                            function,
                            format!(
                                "{} is a fixed parameter: set it before fmi2ExitInitializationMode",
                                v.name
                            ),
                        );
                    }
                    if !x.is_finite() {
                        return err(
                            function,
                            format!("parameter {} = {x} is not finite", v.name),
                        );
                    }
                    if kind == Kind::Integer && !integer_allowed(v.name, x as i32) {
                        return err(
                            function,
                            format!(
                                "{} = {x} is not an allowed value ({})",
                                v.name, v.description
                            ),
                        );
                    }
                    set(&mut params, x);
                }
            }
        }
        self.params = params;
        self.inputs = inputs;
        self.input_slopes = slopes;
        Ok(())
    }

    /// fmi2SetRealInputDerivatives: first-order slopes of the inputs for the next
    /// fmi2DoStep only (FMI 2.0 section 4.2.1: the derivatives belong to the inputs set for
    /// that communication step; the step consumes them and a new input value clears them).
    pub fn set_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> Result<()> {
        const F: &str = "fmi2SetRealInputDerivatives";
        self.allowed(
            F,
            &[
                Phase::Instantiated,
                Phase::InitializationMode,
                Phase::StepComplete,
            ],
        )?;
        let mut slopes = self.input_slopes;
        for ((&vr, &order), &x) in vrs.iter().zip(orders).zip(values) {
            let v = Self::variable(F, vr, Kind::Real)?;
            let Role::Input(k) = v.role else {
                return err(F, format!("{} is not an input", v.name));
            };
            if order != 1 {
                return err(F, format!("derivative order {order} of {}: only order 1 is supported (maxOutputDerivativeOrder=0, linear interpolation)", v.name));
            }
            if !x.is_finite() {
                return err(F, format!("derivative of {} = {x} is not finite", v.name));
            }
            slopes[k] = x;
        }
        self.input_slopes = slopes;
        Ok(())
    }

    /// fmi2DoStep: advance from `t` (must be the current time) by `h`.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<()> {
        const F: &str = "fmi2DoStep";
        self.allowed(F, &[Phase::StepComplete])?;
        if !(h.is_finite() && h > 0.0) {
            return err(
                F,
                format!("communicationStepSize {h} must be finite and > 0"),
            );
        }
        let tol = comm_point_tolerance(self.time_s, h);
        if !t.is_finite() || (t - self.time_s).abs() > tol {
            return err(
                F,
                format!(
                    "currentCommunicationPoint {t} is not the current time {} (tolerance {tol:e} s)",
                    self.time_s
                ),
            );
        }
        let advance = (t + h) - t;
        if (advance - h).abs() > TIME_RESOLUTION_FRACTION * h {
            return err(
                F,
                format!(
                    "communicationStepSize {h} s cannot be resolved at time {t} s \
                     (t + h - t = {advance} s in double precision); time cannot advance"
                ),
            );
        }
        let from = inputs_from(&self.inputs);
        let end: [f64; 4] = std::array::from_fn(|k| self.inputs[k] + self.input_slopes[k] * h);
        if end.iter().any(|x| !x.is_finite()) {
            return err(
                F,
                "inputs extrapolated with their derivatives are not finite",
            );
        }
        let to = inputs_from(&end);
        let Some(sim) = self.sim.as_mut() else {
            return err(F, "internal: no simulator after initialization");
        };
        sim.advance(h, &from, &to, &SensorNoise::default());
        // the end time exactly, without drift from repeated addition
        sim.time_s = t + h;
        if let Some(why) = sim.diverged() {
            self.phase = Phase::Error;
            return err(F, why);
        }
        self.time_s = sim.time_s;
        // the step applied the inputs up to its end: outputs and later steps start there,
        // and the derivatives were for this step only
        self.inputs = end;
        self.input_slopes = [0.0; 4];
        Ok(())
    }

    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            phase: self.phase,
            params: self.params,
            time_s: self.time_s,
            start_time_s: self.start_time_s,
            inputs: self.inputs,
            input_slopes: self.input_slopes,
            state: self.sim.as_ref().map(|s| s.state.to_vec()),
            history: self
                .sim
                .as_ref()
                .map(|s| s.history.entries().copied().collect())
                .unwrap_or_default(),
        }
    }

    pub fn restore(&mut self, s: &Snapshot) -> Result<()> {
        const F: &str = "fmi2SetFMUstate";
        self.allowed(
            F,
            &[
                Phase::Instantiated,
                Phase::InitializationMode,
                Phase::StepComplete,
                Phase::EventMode,
                Phase::ContinuousTimeMode,
                Phase::Terminated,
                Phase::Error,
            ],
        )?;
        if let Err(e) = s.params.validate() {
            return err(
                F,
                format!("the state holds invalid parameters: {}", params_message(&e)),
            );
        }
        if let Err(why) = s.check_finite() {
            return err(F, why);
        }
        self.sim = match &s.state {
            Some(x) => {
                let mut sim =
                    Simulator::new(Model::new(&s.params), s.time_s, DEFAULT_MAX_SUBSTEP_S);
                if x.len() != sim.state.len() {
                    return err(
                        F,
                        format!(
                            "state vector of {} values, expected {}",
                            x.len(),
                            sim.state.len()
                        ),
                    );
                }
                sim.state.copy_from_slice(x);
                sim.history = CommandHistory::from_entries(s.history.clone());
                Some(sim)
            }
            None => None,
        };
        self.phase = s.phase;
        self.params = s.params;
        self.time_s = s.time_s;
        self.start_time_s = s.start_time_s;
        self.inputs = s.inputs;
        self.input_slopes = s.input_slopes;
        Ok(())
    }
}

/// Tag of a serialised FMU state.
pub const STATE_FORMAT: &str = "shaketable-fmustate";

/// Version of the serialised layout and meaning. 2: input derivatives apply to one step
/// only (version 1 states carried derivatives that kept acting, so they are refused).
pub const STATE_FORMAT_VERSION: u64 = 2;

/// Serialised FMU state: a format tag and version, then JSON with every float as its bit
/// pattern so the round trip is exact.
pub fn serialize(s: &Snapshot) -> Vec<u8> {
    let bits = |x: f64| x.to_bits();
    let v = serde_json::json!({
        "format": STATE_FORMAT,
        "version": STATE_FORMAT_VERSION,
        "writer": concat!("shaketable ", env!("CARGO_PKG_VERSION")),
        "phase": s.phase,
        "params": s.params.to_toml_string(),
        "time": bits(s.time_s),
        "start": bits(s.start_time_s),
        "inputs": s.inputs.map(bits),
        "slopes": s.input_slopes.map(bits),
        "state": s.state.as_ref().map(|x| x.iter().map(|y| y.to_bits()).collect::<Vec<u64>>()),
        "history": s.history.iter().map(|(t, u)| [t.to_bits(), u.to_bits()]).collect::<Vec<_>>(),
    });
    v.to_string().into_bytes()
}

/// The format version of a serialised state: the tag of this format (or the version-1
/// tag `shaketable-fmustate-1`), and a version equal to ours; a mismatch names both.
fn check_format(v: &serde_json::Value) -> std::result::Result<(), String> {
    let found = match v["format"].as_str() {
        Some(STATE_FORMAT) => v["version"].as_u64(),
        Some(tag) => match tag.strip_prefix("shaketable-fmustate-") {
            Some(n) => n.parse::<u64>().ok(),
            None => {
                return Err(format!(
                "not a serialized ShakeTable state (format tag {tag:?}, expected {STATE_FORMAT:?})"
            ))
            }
        },
        None => return Err("not a serialized ShakeTable state (no format tag)".into()),
    };
    let writer = v["writer"].as_str().unwrap_or("an earlier shaketable");
    match found {
        Some(STATE_FORMAT_VERSION) => Ok(()),
        Some(n) => Err(format!(
            "serialized state format version {n} (written by {writer}), this FMU reads version \
             {STATE_FORMAT_VERSION} (shaketable {}): save the state again with this FMU",
            env!("CARGO_PKG_VERSION")
        )),
        None => Err(format!(
            "serialized state has no valid format version (expected {STATE_FORMAT_VERSION})"
        )),
    }
}

pub fn deserialize(bytes: &[u8]) -> std::result::Result<Snapshot, String> {
    let v: serde_json::Value = serde_json::from_slice(bytes)
        .map_err(|e| format!("not a serialized ShakeTable state: {e}"))?;
    check_format(&v)?;
    let f = |x: &serde_json::Value| -> std::result::Result<f64, String> {
        x.as_u64()
            .map(f64::from_bits)
            .ok_or_else(|| format!("bad number {x}"))
    };
    let arr4 = |x: &serde_json::Value| -> std::result::Result<[f64; 4], String> {
        let a = x.as_array().filter(|a| a.len() == 4).ok_or("bad array")?;
        Ok([f(&a[0])?, f(&a[1])?, f(&a[2])?, f(&a[3])?])
    };
    let params = Params::from_toml_str(
        v["params"].as_str().ok_or("missing params")?,
        "<serialized state>",
    )
    .map_err(|e| params_message(&e))?;
    let state = match &v["state"] {
        serde_json::Value::Null => None,
        x => Some(
            x.as_array()
                .ok_or("bad state")?
                .iter()
                .map(f)
                .collect::<std::result::Result<Vec<f64>, String>>()?,
        ),
    };
    let history = v["history"]
        .as_array()
        .ok_or("bad history")?
        .iter()
        .map(|p| -> std::result::Result<(f64, f64), String> {
            let a = p
                .as_array()
                .filter(|a| a.len() == 2)
                .ok_or("bad history entry")?;
            Ok((f(&a[0])?, f(&a[1])?))
        })
        .collect::<std::result::Result<Vec<_>, String>>()?;
    let snap = Snapshot {
        phase: serde_json::from_value(v["phase"].clone()).map_err(|e| e.to_string())?,
        params,
        time_s: f(&v["time"])?,
        start_time_s: f(&v["start"])?,
        inputs: arr4(&v["inputs"])?,
        input_slopes: arr4(&v["slopes"])?,
        state,
        history,
    };
    snap.check_finite()?;
    Ok(snap)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn running() -> Instance {
        let mut i = Instance::new("t", Params::trees_lab());
        i.setup_experiment(0.0, None).unwrap();
        i.enter_initialization_mode().unwrap();
        i.exit_initialization_mode().unwrap();
        i
    }

    #[test]
    fn state_machine_refuses_calls_out_of_order() {
        let mut i = Instance::new("t", Params::trees_lab());
        assert!(i.do_step(0.0, 0.01).is_err());
        assert!(i.exit_initialization_mode().is_err());
        let mut i = running();
        assert!(i.setup_experiment(0.0, None).is_err());
        // a parameter after initialization
        let e = i
            .set("fmi2SetReal", Kind::Real, &[130], &[1.0])
            .unwrap_err();
        assert!(e.message.contains("table.mass"), "{e}");
        assert!(i.do_step(0.0, -1.0).is_err());
        assert!(i.do_step(0.0, f64::NAN).is_err());
        assert!(i
            .do_step(0.5, 0.01)
            .unwrap_err()
            .message
            .contains("current time"));
        assert!(i.set("fmi2SetReal", Kind::Real, &[0], &[f64::NAN]).is_err());
        assert!(i
            .set("fmi2SetReal", Kind::Real, &[999], &[1.0])
            .unwrap_err()
            .message
            .contains("999"));
        i.do_step(0.0, 0.01).unwrap();
        i.terminate().unwrap();
        assert!(i.do_step(0.01, 0.01).is_err());
        i.reset();
        assert_eq!(i.phase, Phase::Instantiated);
    }

    #[test]
    fn invalid_parameters_fail_at_exit_initialization() {
        let mut i = Instance::new("t", Params::trees_lab());
        i.enter_initialization_mode().unwrap();
        i.set("fmi2SetReal", Kind::Real, &[130], &[-1.0]).unwrap();
        let e = i.exit_initialization_mode().unwrap_err();
        assert!(e.message.contains("mass"), "{e}");
        assert!(i
            .set("fmi2SetInteger", Kind::Integer, &[110], &[7.0])
            .is_err());
    }

    #[test]
    fn snapshot_serialization_round_trips_bit_for_bit() {
        let mut i = running();
        i.set("fmi2SetReal", Kind::Real, &[0, 1], &[0.001, 0.01])
            .unwrap();
        for k in 0..50 {
            i.do_step(k as f64 / 512.0, 1.0 / 512.0).unwrap();
        }
        let s = i.snapshot();
        let back = deserialize(&serialize(&s)).unwrap();
        assert_eq!(back, s);
    }
}
