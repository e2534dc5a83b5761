//! One FMU instance as safe Rust: the FMI 2.0 Co-Simulation state machine with every call
//! checked against the state it is allowed in and against its arguments. The C exports
//! (`export.rs`) only translate pointers and log the errors returned here.
//!
//! Here: the phases, errors, the lifecycle and stepping; `values.rs`: get and set by value
//! reference; `snapshot.rs`: the FMU state and its serialisation.

mod snapshot;
mod values;

pub use snapshot::{deserialize, serialize, Snapshot, STATE_FORMAT, STATE_FORMAT_VERSION};

use super::variables::{inputs_from, Kind, Role, VARIABLES};
use crate::model::SensorNoise;
use crate::params::{Params, ParamsError};
use crate::solver::{Simulator, DEFAULT_MAX_SUBSTEP_S};
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

    /// Validates the parameters and starts the simulator; `Some` warning when the closed
    /// loop at rest is unstable (spec section 8). Only parameters that passed validation
    /// are linearised: the poles of refused (non-finite, absurd) ones mean nothing.
    pub fn exit_initialization_mode(&mut self) -> Result<Option<String>> {
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
        Ok(crate::linear::stability_warning(&self.params))
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
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn running() -> Instance {
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
}
