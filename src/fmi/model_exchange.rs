//! FMI 2.0 Model Exchange over [`Instance`]: the importer's integrator owns time and the
//! continuous states; the FMU gives derivatives from the model's one derivative function
//! ([`crate::Model::derivatives`]) and event indicators where the model switches
//! ([`crate::model::switching`]). The model has no discrete states, so an event only
//! restarts the integration at the kink.

use super::instance::{FmiError, Instance, Interface, Phase};
use super::variables::inputs_from;
use crate::model::switching::SWITCH_COUNT;
use crate::model::{ix, NX};
use crate::solver::Simulator;

/// Number of continuous states the FMU declares (the model's fixed state vector).
pub const STATE_COUNT: usize = NX;
/// Number of event indicators (the model's switching functions).
pub const EVENT_INDICATOR_COUNT: usize = SWITCH_COUNT;

type Result<T> = std::result::Result<T, FmiError>;

fn err<T>(function: &'static str, message: impl Into<String>) -> Result<T> {
    Err(FmiError {
        function,
        message: message.into(),
    })
}

/// Phases in which the integrator may read states, derivatives and indicators.
const READABLE: [Phase; 4] = [
    Phase::InitializationMode,
    Phase::EventMode,
    Phase::ContinuousTimeMode,
    Phase::Terminated,
];

impl Instance {
    fn model_exchange(&self, function: &'static str, phases: &[Phase]) -> Result<()> {
        if self.interface != Interface::ModelExchange {
            return err(function, "this instance was instantiated for Co-Simulation");
        }
        if !phases.contains(&self.phase) {
            return err(
                function,
                format!(
                    "not allowed in state {:?} (allowed in {phases:?})",
                    self.phase
                ),
            );
        }
        Ok(())
    }

    fn running_simulation(&mut self, function: &'static str) -> Result<&mut Simulator> {
        match self.sim.as_mut() {
            Some(s) => Ok(s),
            None => err(function, "internal: no simulator after initialization"),
        }
    }

    /// fmi2SetTime.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        const F: &str = "fmi2SetTime";
        self.model_exchange(F, &[Phase::EventMode, Phase::ContinuousTimeMode])?;
        if !t.is_finite() {
            return err(F, format!("time {t} is not finite"));
        }
        self.running_simulation(F)?.time_s = t;
        self.time_s = t;
        Ok(())
    }

    /// fmi2SetContinuousStates: every state, in [`crate::model::ix`] order.
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Result<()> {
        const F: &str = "fmi2SetContinuousStates";
        self.model_exchange(F, &[Phase::EventMode, Phase::ContinuousTimeMode])?;
        if x.len() != STATE_COUNT {
            return err(
                F,
                format!("nx = {}, this FMU has {STATE_COUNT} states", x.len()),
            );
        }
        if let Some(k) = x.iter().position(|v| !v.is_finite()) {
            return err(F, format!("state {k} = {} is not finite", x[k]));
        }
        self.running_simulation(F)?.state.copy_from_slice(x);
        Ok(())
    }

    /// fmi2GetContinuousStates (the rest state before initialization ends).
    pub fn continuous_states(&self, out: &mut [f64]) -> Result<()> {
        const F: &str = "fmi2GetContinuousStates";
        self.model_exchange(F, &READABLE)?;
        check_len(F, out.len(), STATE_COUNT)?;
        out.copy_from_slice(&self.simulation().state);
        Ok(())
    }

    /// fmi2GetDerivatives at the current time, states and inputs.
    pub fn derivatives(&self, out: &mut [f64]) -> Result<()> {
        const F: &str = "fmi2GetDerivatives";
        self.model_exchange(F, &READABLE)?;
        check_len(F, out.len(), STATE_COUNT)?;
        let ds = self
            .simulation()
            .derivatives_now(&inputs_from(&self.inputs));
        out.copy_from_slice(&ds);
        Ok(())
    }

    /// fmi2GetEventIndicators: the model's switching functions.
    pub fn event_indicators(&self, out: &mut [f64]) -> Result<()> {
        const F: &str = "fmi2GetEventIndicators";
        self.model_exchange(F, &READABLE)?;
        check_len(F, out.len(), EVENT_INDICATOR_COUNT)?;
        let sim = self.simulation();
        let z = sim
            .model
            .switching_functions(&sim.state, &inputs_from(&self.inputs));
        out.copy_from_slice(&z);
        Ok(())
    }

    /// fmi2GetNominalsOfContinuousStates: the scale of each state for the integrator's
    /// absolute tolerance (stroke, velocity limit, supply pressure, full spool).
    pub fn state_nominals(&self, out: &mut [f64]) -> Result<()> {
        const F: &str = "fmi2GetNominalsOfContinuousStates";
        self.model_exchange(
            F,
            &[
                Phase::Instantiated,
                Phase::InitializationMode,
                Phase::EventMode,
                Phase::ContinuousTimeMode,
                Phase::Terminated,
            ],
        )?;
        check_len(F, out.len(), STATE_COUNT)?;
        out.copy_from_slice(&state_nominals(&self.params));
        Ok(())
    }

    /// fmi2EnterEventMode.
    pub fn enter_event_mode(&mut self) -> Result<()> {
        const F: &str = "fmi2EnterEventMode";
        self.model_exchange(F, &[Phase::EventMode, Phase::ContinuousTimeMode])?;
        self.phase = Phase::EventMode;
        Ok(())
    }

    /// fmi2NewDiscreteStates: nothing discrete changes; no time event is ever scheduled.
    pub fn new_discrete_states(&mut self) -> Result<()> {
        self.model_exchange("fmi2NewDiscreteStates", &[Phase::EventMode])
    }

    /// fmi2EnterContinuousTimeMode.
    pub fn enter_continuous_time_mode(&mut self) -> Result<()> {
        self.model_exchange("fmi2EnterContinuousTimeMode", &[Phase::EventMode])?;
        self.phase = Phase::ContinuousTimeMode;
        Ok(())
    }

    /// fmi2CompletedIntegratorStep: the accepted state must stay inside the operating
    /// envelope (spec section 8), as fmi2DoStep checks in Co-Simulation.
    pub fn completed_integrator_step(&mut self) -> Result<()> {
        const F: &str = "fmi2CompletedIntegratorStep";
        self.model_exchange(F, &[Phase::ContinuousTimeMode])?;
        if let Some(why) = self.running_simulation(F)?.diverged() {
            self.phase = Phase::Error;
            return err(F, why);
        }
        Ok(())
    }
}

fn check_len(function: &'static str, got: usize, want: usize) -> Result<()> {
    if got == want {
        Ok(())
    } else {
        err(
            function,
            format!("array of {got} values, this FMU has {want}"),
        )
    }
}

/// Scale of each state: its size in ordinary operation (the integrator's absolute
/// tolerance is its relative tolerance times this).
pub fn state_nominals(p: &crate::params::Params) -> [f64; STATE_COUNT] {
    let stroke = p.limits.stroke_m;
    let speed = p.limits.velocity_m_s;
    let pressure = p.actuator.supply_pressure_pa;
    // a full spool is 1; its speed scale is the valve's bandwidth times that
    let spool_speed = 2.0 * std::f64::consts::PI * p.servovalve.natural_frequency_hz.max(1.0);
    let mut n = [1.0; STATE_COUNT];
    n[ix::XV] = 1.0;
    n[ix::XV_DOT] = spool_speed;
    n[ix::PA] = pressure;
    n[ix::PB] = pressure;
    n[ix::X] = stroke;
    n[ix::V] = speed;
    n[ix::Z] = 1.0;
    n[ix::XS] = stroke;
    n[ix::VS] = speed;
    n[ix::XF] = stroke;
    n[ix::VF] = speed;
    n[ix::XS2] = stroke;
    n[ix::VS2] = speed;
    n[ix::XS3] = stroke;
    n[ix::VS3] = speed;
    n[ix::XR] = stroke;
    n[ix::VR] = speed;
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{Params, ServovalveModel};

    fn exchange(p: Params) -> Instance {
        let mut i = Instance::new("me", p);
        i.interface = Interface::ModelExchange;
        i.enter_initialization_mode().unwrap();
        i
    }

    #[test]
    fn model_exchange_walks_its_modes_and_starts_at_rest() {
        let mut i = exchange(Params::trees_lab());
        i.exit_initialization_mode().unwrap();
        assert_eq!(i.phase, Phase::EventMode);
        assert!(
            i.do_step(0.0, 1e-3).is_err(),
            "fmi2DoStep is Co-Simulation only"
        );
        i.new_discrete_states().unwrap();
        i.enter_continuous_time_mode().unwrap();
        let mut ds = [1.0; STATE_COUNT];
        i.derivatives(&mut ds).unwrap();
        assert!(ds.iter().all(|d| d.abs() < 1e-6), "at rest: {ds:?}");
        // a displacement reference opens the valve: the spool starts to move
        i.inputs[0] = 0.01;
        i.derivatives(&mut ds).unwrap();
        assert!(ds[ix::XV_DOT] > 0.0);
        assert!(i.set_continuous_states(&[0.0; 3]).is_err());
        assert!(i.set_continuous_states(&[f64::NAN; STATE_COUNT]).is_err());
        i.completed_integrator_step().unwrap();
    }

    #[test]
    fn the_delay_valve_is_refused_and_the_state_leaving_the_envelope_is_an_error() {
        let mut p = Params::trees_lab();
        p.servovalve.model = ServovalveModel::Delay;
        let e = exchange(p).exit_initialization_mode().unwrap_err();
        assert!(e.message.contains("Model Exchange"), "{e}");
        let mut i = exchange(Params::trees_lab());
        i.exit_initialization_mode().unwrap();
        i.enter_continuous_time_mode().unwrap();
        let mut x = [0.0; STATE_COUNT];
        i.continuous_states(&mut x).unwrap();
        x[ix::X] = 10.0 * Params::trees_lab().limits.stroke_m;
        i.set_continuous_states(&x).unwrap();
        assert!(i.completed_integrator_step().is_err());
        assert_eq!(i.phase, Phase::Error);
    }
}
