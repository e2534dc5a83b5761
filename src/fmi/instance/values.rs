//! Reading and writing an instance's variables by value reference (fmi2Get/fmi2Set and the
//! input derivatives), each checked against the state machine and the variable table.

use super::*;
use crate::fmi::variables::{by_vr, integer_allowed, Variable};

impl Instance {
    fn variable(function: &'static str, vr: u32, kind: Kind) -> Result<&'static Variable> {
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
}
