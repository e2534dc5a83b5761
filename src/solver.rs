//! Fixed-step time integration of the model: classical Runge-Kutta 4 with sub-steps inside
//! each sample interval, inputs linearly interpolated across the interval (campaign format),
//! sensor noise held constant over it (spec section 2). Deterministic bit for bit: no
//! adaptive control, no threads, no allocation per step once the delay history has grown.

use crate::model::{Inputs, Model, Outputs, SensorNoise, State, NX};
use std::collections::VecDeque;

mod pair;
mod record;
pub use pair::simulate_run_pair;
pub use record::*;

/// Default largest sub-step: 1/3072 s, i.e. 6 sub-steps per 512 Hz sample. Halving it
/// changes the outputs of the paper's random tests by about 5e-7 of their RMS (RK4,
/// error ~ h^4; tests/solver.rs asserts < 1e-6).
pub const DEFAULT_MAX_SUBSTEP_S: f64 = 1.0 / 3072.0;

/// Upper bound on sub-steps per interval, so a runaway state cannot stall a run.
pub const MAX_SUBSTEPS_PER_INTERVAL: usize = 100_000;

/// A table moving faster than this many times its valve's no-load speed at full opening
/// (`Kq / A`, 2.2 m/s with the defaults) has left the physics the model describes: the
/// run has gone unstable ([`Simulator::diverged`]).
pub const DIVERGED_SPEED_FACTOR: f64 = 10.0;

/// Where in a step the classical Runge-Kutta 4 scheme evaluates the derivative.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rk4Stage {
    /// At the start of the step (k1).
    Start,
    /// At its midpoint (k2 and k3).
    Middle,
    /// At its end (k4).
    End,
}

impl Rk4Stage {
    /// The time of this stage in the step of length `h_s` starting at `t_s`.
    #[inline]
    pub fn time_s(self, t_s: f64, h_s: f64) -> f64 {
        match self {
            Rk4Stage::Start => t_s,
            Rk4Stage::Middle => t_s + 0.5 * h_s,
            Rk4Stage::End => t_s + h_s,
        }
    }
}

/// One classical Runge-Kutta 4 step of length `h_s`, state `x` advanced in place:
/// `derivative(stage, x, dx)` writes every `dx/dt` at state `x` and the time `stage` names
/// (the midpoint twice). The solver's sub-step and the spool fit's
/// ([`crate::identify::spool`]); allocation-free. A hot caller marks its closure
/// `#[inline(always)]` (the four stages then compile as if written out).
#[inline(always)]
pub fn rk4_step<const N: usize>(
    x: &mut [f64; N],
    h_s: f64,
    derivative: impl FnMut(Rk4Stage, &[f64; N], &mut [f64; N]),
) {
    rk4_step_leading::<N, N>(x, h_s, derivative)
}

/// [`rk4_step`] that advances only the leading `M` states: the caller guarantees that the
/// derivative of every later state is exactly zero (a state of a switched-off part), so
/// they keep their values, as the full step would keep them bit for bit.
#[inline(always)]
pub fn rk4_step_leading<const N: usize, const M: usize>(
    x: &mut [f64; N],
    h_s: f64,
    mut derivative: impl FnMut(Rk4Stage, &[f64; N], &mut [f64; N]),
) {
    let h = h_s;
    let mut k1 = [0.0; N];
    let mut k2 = [0.0; N];
    let mut k3 = [0.0; N];
    let mut k4 = [0.0; N];
    let mut at = *x;
    derivative(Rk4Stage::Start, x, &mut k1);
    for j in 0..M {
        at[j] = x[j] + 0.5 * h * k1[j];
    }
    derivative(Rk4Stage::Middle, &at, &mut k2);
    for j in 0..M {
        at[j] = x[j] + 0.5 * h * k2[j];
    }
    derivative(Rk4Stage::Middle, &at, &mut k3);
    for j in 0..M {
        at[j] = x[j] + h * k3[j];
    }
    derivative(Rk4Stage::End, &at, &mut k4);
    for j in 0..M {
        x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    }
}

/// History of the valve command for the `delay` servovalve (spec section 3):
/// `(time, u)` pairs at every sub-step end, linearly interpolated.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CommandHistory {
    entries: VecDeque<(f64, f64)>,
}

impl CommandHistory {
    /// `u(t)`: zero before the first entry (the table was at rest), the last entry
    /// beyond it (a delay shorter than a sub-step is resolved to the sub-step).
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        let n = self.entries.len();
        if n == 0 || t < self.entries[0].0 {
            return 0.0;
        }
        let i = self.entries.partition_point(|e| e.0 <= t);
        if i >= n {
            return self.entries[n - 1].1;
        }
        let (t0, u0) = self.entries[i - 1];
        let (t1, u1) = self.entries[i];
        u0 + (u1 - u0) * (t - t0) / (t1 - t0)
    }

    /// Append `u(t)` and forget entries no longer needed for a delay `tau`.
    #[inline]
    pub fn push(&mut self, t: f64, u: f64, tau: f64) {
        if let Some(&(last, _)) = self.entries.back() {
            if t <= last {
                return;
            }
        }
        self.entries.push_back((t, u));
        while self.entries.len() > 2 && self.entries[1].0 < t - tau {
            self.entries.pop_front();
        }
    }

    pub fn clear(&mut self) {
        self.entries.clear();
    }

    pub fn entries(&self) -> impl Iterator<Item = &(f64, f64)> {
        self.entries.iter()
    }

    pub fn from_entries(entries: Vec<(f64, f64)>) -> Self {
        CommandHistory {
            entries: entries.into(),
        }
    }
}

/// A running simulation: model, state, time and the command history.
#[derive(Debug, Clone)]
pub struct Simulator {
    pub model: Model,
    pub state: State,
    pub time_s: f64,
    pub history: CommandHistory,
    pub max_substep_s: f64,
    /// What [`Simulator::diverged`] checks.
    pub checks: Checks,
    /// Modulus of the fastest closed-loop pole at rest, rad/s ([`fastest_pole_rad_s`]):
    /// the sub-steps resolve it.
    fastest_pole_rad_s: f64,
}

/// Largest product of the sub-step and the fastest closed-loop pole at rest: RK4 is
/// stable up to about 2.8 on a real pole and on an undamped oscillator; 2 keeps a margin,
/// and a mode that fast is over within a few sub-steps (the physical modes of a table sit
/// far below it). A fitted valve or oil column can be far faster than the TREES Lab
/// table's: a second-order valve at 219 Hz with damping 4.1, fitted on the UTFSM
/// actuator, has a pole at 11 000 rad/s, 11 times what a 1/1024-s sub-step holds, and
/// every run of it diverged. The TREES Lab table's fastest pole (about 180 rad/s) is far
/// below what the default sub-step holds (6144 rad/s), so its runs are unchanged.
pub const POLE_STEP: f64 = 2.0;

/// Most sub-steps per interval the fastest pole may ask for (with [`POLE_STEP`], poles to
/// 16 times the sampling rate in rad/s): a faster pole is beyond anything a record can
/// show, and is an optimiser's wandering trial (an identification's trial valves at
/// kilohertz made its runs 30 times slower and the UTFSM identification took minutes);
/// its run may diverge, as it did before, and costs the fit one short run. The grey-box
/// fit refuses such trials outright ([`within_pole_reach`]).
pub const MAX_POLE_SUBSTEPS: f64 = 8.0;

/// The fastest closed-loop pole (rad/s) the sub-steps integrate faithfully at
/// `sample_rate_hz`: [`POLE_STEP`] per sub-step, at most [`MAX_POLE_SUBSTEPS`] sub-steps a
/// sample. A faster pole is integrated ever less damped, up to RK4's edge of stability
/// (2.785 times a sub-step's rate on the real axis), where its mode is not damped at all:
/// a fit may then exploit the integrator, not the data (the UTFSM closed-loop fit put an
/// overdamped valve's fast pole at 2.785 times the sub-step's rate, to the third digit).
pub fn pole_reach_rad_s(sample_rate_hz: f64) -> f64 {
    POLE_STEP * MAX_POLE_SUBSTEPS * sample_rate_hz
}

/// Whether `model`'s fastest pole at rest is within [`pole_reach_rad_s`] of
/// `sample_rate_hz`.
pub fn within_pole_reach(model: &Model, sample_rate_hz: f64) -> bool {
    within_pole_reach_of(model, pole_reach_rad_s(sample_rate_hz))
}

/// Whether `model`'s fastest pole at rest is at most `reach_rad_s`.
pub fn within_pole_reach_of(model: &Model, reach_rad_s: f64) -> bool {
    fastest_pole_rad_s(model) <= reach_rad_s
}

/// Modulus of the fastest pole of the closed loop linearised at rest (rad/s), 0 when it
/// cannot be computed. The delay valve is taken as its first-order lag (the delay is
/// not a state of the simulation).
fn fastest_pole_rad_s(model: &Model) -> f64 {
    let mut p = model.params;
    if p.servovalve.model == crate::params::ServovalveModel::Delay {
        p.servovalve.model = crate::params::ServovalveModel::FirstOrder;
    }
    crate::linear::Linearisation::new(&p)
        .poles()
        .and_then(|poles| poles.last().map(|z| z.norm()))
        .filter(|r| r.is_finite())
        .unwrap_or(0.0)
}

/// What stops a run ([`Simulator::diverged`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Checks {
    /// The operating envelope (spec section 8) and the numerical guards: every run a
    /// user sees (simulate, synth, the FMU).
    #[default]
    Envelope,
    /// Only a non-finite state and the [`DIVERGED_SPEED_FACTOR`] guard: for the
    /// diagnosis' output-error fits, whose trial models may pass the envelope on their way
    /// to the data (an optimiser needs a finite cost there); their results are held to
    /// the envelope when they are scored.
    DivergenceOnly,
}

/// Linear interpolation of the inputs at fraction `w` of the interval.
#[inline]
fn lerp(a: &Inputs, b: &Inputs, w: f64) -> Inputs {
    let l = |x: f64, y: f64| x + (y - x) * w;
    Inputs {
        reference: crate::model::Reference {
            displacement_m: l(a.reference.displacement_m, b.reference.displacement_m),
            velocity_m_s: l(a.reference.velocity_m_s, b.reference.velocity_m_s),
            acceleration_m_s2: l(a.reference.acceleration_m_s2, b.reference.acceleration_m_s2),
        },
        external_force_n: l(a.external_force_n, b.external_force_n),
    }
}

/// Largest phase the free-play contact's oscillation advances per sub-step, rad: RK4 is
/// stable up to about 2.8 rad on an undamped oscillator; 0.5 rad (13 sub-steps a cycle)
/// keeps its amplitude error near 0.1 % a cycle.
pub const CONTACT_STEP_RAD: f64 = 0.5;

impl Simulator {
    /// A table at rest at time `start_s`.
    pub fn new(model: Model, start_s: f64, max_substep_s: f64) -> Simulator {
        let state = model.rest_state();
        let fastest_pole_rad_s = fastest_pole_rad_s(&model);
        Simulator {
            fastest_pole_rad_s,
            model,
            state,
            time_s: start_s,
            history: CommandHistory::default(),
            max_substep_s,
            checks: Checks::Envelope,
        }
    }

    fn tau(&self) -> f64 {
        self.model.valve.tau_s
    }

    #[inline]
    fn delayed_command(&self, t: f64) -> f64 {
        if self.model.has_delay() {
            self.history.at(t - self.tau())
        } else {
            0.0
        }
    }

    /// The readings at the current time for the given inputs and noise.
    pub fn outputs(&self, inp: &Inputs, noise: &SensorNoise) -> Outputs {
        self.model
            .outputs(&self.state, inp, noise, self.delayed_command(self.time_s))
    }

    /// The state derivatives at the current time for the given inputs (noise-free): what
    /// a Model Exchange importer integrates.
    pub fn derivatives_now(&self, inp: &Inputs) -> State {
        let mut ds = [0.0; NX];
        self.model.derivatives(
            &self.state,
            inp,
            &SensorNoise::default(),
            self.delayed_command(self.time_s),
            &mut ds,
        );
        ds
    }

    #[inline]
    fn record_command(&mut self, inp: &Inputs, noise: &SensorNoise) {
        if self.model.has_delay() {
            let u = self
                .model
                .algebraic(&self.state, inp, noise, self.delayed_command(self.time_s))
                .valve_command;
            let tau = self.tau();
            self.history.push(self.time_s, u, tau);
        }
    }

    /// Why the run must stop, if it must: a state outside the operating envelope
    /// (spec section 8, [`crate::model::limits`]: non-finite, stroke, velocity,
    /// pressure), or the table (relative to the reaction mass) faster than
    /// [`DIVERGED_SPEED_FACTOR`] times the valve's no-load speed at full opening, a
    /// numerical guard for velocity limits set above it. Checked by [`simulate_record`]
    /// and the FMU's `fmi2DoStep`: past this the Bouc-Wen guard of
    /// [`Simulator::substeps`] would spend minutes on ever-finer sub-steps of a
    /// meaningless state.
    pub fn diverged(&self) -> Option<String> {
        let t = self.time_s;
        let limit = match self.checks {
            Checks::Envelope => crate::model::limits::check(&self.model.params, &self.state),
            Checks::DivergenceOnly => self
                .state
                .iter()
                .any(|x| !x.is_finite())
                .then_some(crate::model::limits::Exceeded::NonFinite),
        };
        if let Some(e) = limit {
            return Some(match e {
                crate::model::limits::Exceeded::NonFinite => format!("at t = {t} s: {e}"),
                _ => format!("the run left the table's operating envelope at t = {t} s: {e}"),
            });
        }
        let a = &self.model.params.actuator;
        let limit = DIVERGED_SPEED_FACTOR * a.flow_gain_m3_s / a.piston_area_m2;
        let v = self.state[crate::model::ix::V] - self.state[crate::model::ix::VF];
        (v.abs() > limit).then(|| {
            format!(
                "the simulation diverged at t = {t} s: table velocity {v:.3e} m/s, beyond \
                 {DIVERGED_SPEED_FACTOR} times the valve's full-opening speed Kq/A \
                 ({limit:.3} m/s); the parameters make the run unstable (the control loop, \
                 or the integration at this sub-step)"
            )
        })
    }

    /// Number of sub-steps used for an interval of `dt_s`: at most `max_substep_s` each,
    /// short enough for the fastest pole at rest ([`POLE_STEP`], [`MAX_POLE_SUBSTEPS`]),
    /// and for the Bouc-Wen equation (eq. 4.15), whose rate near `|Z| = 1` is about
    /// `2 |v| / Y`: RK4 is stable for `h * rate < 2.78`; the guard keeps it below 1
    /// (it only acts for a small yield displacement or a fast table: with the defaults,
    /// Y = 1 mm, from 1.5 m/s at 1/3072 s).
    pub fn substeps(&self, dt_s: f64) -> usize {
        let base = ((dt_s / self.max_substep_s) * (1.0 - 1e-12))
            .ceil()
            .max(1.0);
        let v = (self.state[crate::model::ix::V] - self.state[crate::model::ix::VF]).abs();
        let friction_rate = 2.0 * v * self.model.friction.inv_yield;
        // free play: the rod ringing on its contact ([`Model::contact_rate_rad_s`])
        let contact = (dt_s * self.model.contact_rate_rad_s() / CONTACT_STEP_RAD).ceil();
        let poles = (dt_s * self.fastest_pole_rad_s / POLE_STEP)
            .ceil()
            .min(MAX_POLE_SUBSTEPS);
        let guard = (dt_s * friction_rate).ceil().max(contact).max(poles);
        // a non-finite guard (non-finite state) falls back to the base count
        let n = if guard.is_finite() {
            base.max(guard)
        } else {
            base
        };
        n.min(MAX_SUBSTEPS_PER_INTERVAL as f64) as usize
    }

    /// Advance by `dt_s`: inputs go linearly from `from` (now) to `to` (now + dt),
    /// the noise is held. RK4 with [`Simulator::substeps`] equal sub-steps.
    pub fn advance(&mut self, dt_s: f64, from: &Inputs, to: &Inputs, noise: &SensorNoise) {
        let interval = self.interval(dt_s, from, to);
        if self.history.entries.is_empty() {
            self.record_command(from, noise);
        }
        for i in 0..interval.n {
            self.substep(&interval, i, noise);
        }
    }

    /// The next `dt_s` from now in [`Simulator::substeps`] equal sub-steps, the inputs
    /// going from `from` to `to`.
    #[inline(always)]
    fn interval<'a>(&self, dt_s: f64, from: &'a Inputs, to: &'a Inputs) -> Interval<'a> {
        let n = self.substeps(dt_s);
        Interval {
            t0_s: self.time_s,
            dt_s,
            n,
            h_s: dt_s / n as f64,
            from,
            to,
        }
    }

    /// Sub-step `i` of `interval`.
    #[inline(always)]
    fn substep(&mut self, interval: &Interval, i: usize, noise: &SensorNoise) {
        let (t, h) = (interval.time_s(i), interval.h_s);
        // inputs and delayed command at the start, midpoint and end of the sub-step
        let [in0, inm, in1] = interval.inputs(i);
        let (d0, dm, d1) = (
            self.delayed_command(t),
            self.delayed_command(t + 0.5 * h),
            self.delayed_command(t + h),
        );
        let model = &self.model;
        let stages = [(&in0, d0), (&inm, dm), (&in1, d1)];
        if model.core_only() {
            model_step::<{ crate::model::CORE_STATES }>(model, &mut self.state, h, stages, noise);
        } else {
            model_step::<NX>(model, &mut self.state, h, stages, noise);
        }
        model.project(&mut self.state);
        self.time_s = interval.end_time_s(i);
        if model.has_delay() {
            let u = model
                .algebraic(
                    &self.state,
                    &in1,
                    noise,
                    self.history.at(self.time_s - model.valve.tau_s),
                )
                .valve_command;
            self.history.push(self.time_s, u, model.valve.tau_s);
        }
    }
}

/// One sample interval of [`Simulator::advance`]: `n` equal sub-steps of `h_s` from
/// `t0_s`, the inputs going linearly from `from` to `to`.
struct Interval<'a> {
    t0_s: f64,
    dt_s: f64,
    n: usize,
    h_s: f64,
    from: &'a Inputs,
    to: &'a Inputs,
}

impl Interval<'_> {
    /// The start of sub-step `i`.
    #[inline(always)]
    fn time_s(&self, i: usize) -> f64 {
        self.t0_s + i as f64 * self.h_s
    }

    /// The time after sub-step `i` (the interval's end exactly after the last).
    #[inline(always)]
    fn end_time_s(&self, i: usize) -> f64 {
        if i + 1 == self.n {
            self.t0_s + self.dt_s
        } else {
            self.time_s(i) + self.h_s
        }
    }

    /// The inputs at the start, midpoint and end of sub-step `i`.
    #[inline(always)]
    fn inputs(&self, i: usize) -> [Inputs; 3] {
        let n = self.n as f64;
        let w0 = (i as f64) / n;
        let wm = (i as f64 + 0.5) / n;
        let w1 = (i as f64 + 1.0) / n;
        [
            lerp(self.from, self.to, w0),
            lerp(self.from, self.to, wm),
            lerp(self.from, self.to, w1),
        ]
    }
}

/// One RK4 sub-step of `model` advancing its leading `M` states ([`rk4_step_leading`]),
/// with the inputs and delayed command at the step's start, midpoint and end.
#[inline(always)]
fn model_step<const M: usize>(
    model: &Model,
    state: &mut State,
    h: f64,
    stages: [(&Inputs, f64); 3],
    noise: &SensorNoise,
) {
    rk4_step_leading::<NX, M>(
        state,
        h,
        #[inline(always)]
        |stage, x, dx| {
            let (inp, delayed) = rk4_stage_inputs(&stages, stage);
            model.derivatives(x, inp, noise, delayed, dx);
        },
    );
}

/// What a stage of a sub-step reads from its start, midpoint and end values.
#[inline(always)]
fn rk4_stage_inputs<T: Copy>(at: &[T; 3], stage: Rk4Stage) -> T {
    match stage {
        Rk4Stage::Start => at[0],
        Rk4Stage::Middle => at[1],
        Rk4Stage::End => at[2],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RK4 on the harmonic oscillator `x'' = -w^2 x`: one period in 64 steps returns to
    /// the start within the scheme's `(w h)^4` per-period error, the stages at the step's
    /// start, midpoint (twice) and end.
    #[test]
    fn rk4_step_integrates_an_oscillator_to_fourth_order() {
        let (w, n) = (2.0 * std::f64::consts::PI, 64);
        let h = 1.0 / n as f64;
        let mut x = [1.0, 0.0];
        let mut stages = Vec::new();
        for _ in 0..n {
            rk4_step(&mut x, h, |stage, s, ds| {
                stages.push(stage);
                *ds = [s[1], -w * w * s[0]];
            });
        }
        assert!((x[0] - 1.0).abs() < 1e-4 && x[1].abs() < 1e-3, "{x:?}");
        use Rk4Stage::*;
        assert_eq!(stages[..4], [Start, Middle, Middle, End]);
        assert_eq!(Middle.time_s(1.0, 0.5), 1.25);
    }
}
