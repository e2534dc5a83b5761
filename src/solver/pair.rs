//! Two independent runs advanced together, sub-step by sub-step: a run is latency bound
//! (each RK4 stage waits on the derivative chain of the one before: forces, acceleration,
//! command, valve), so the processor overlaps a second run's independent chain almost for
//! free. Each run computes exactly what it computes alone ([`Simulator::advance`], the
//! same sub-step interval and arithmetic), so the outputs are the same bit for bit; only the
//! bare table without a delay valve is paired ([`Simulator::pairable`]), anything else
//! advances alone.

use super::Rk4Stage;
use super::{rk4_stage_inputs, Checks, Diverged, Run, Simulator, Stop, NX};
use crate::model::{Inputs, Model, Outputs, SensorNoise, State, CORE_STATES};

impl Simulator {
    /// Whether [`advance_pair`] may advance this simulator: the bare table (the RK4 step
    /// of its leading states) and no command history (no delay valve).
    fn pairable(&self) -> bool {
        self.model.core_only() && !self.model.has_delay()
    }
}

/// Two RK4 steps of the leading `M` states, stage by stage interleaved: each as
/// [`super::rk4_step_leading`] computes it. Written out rather than calling that step
/// twice: the point of the pair is that the two runs' derivative chains overlap within
/// each stage, which two calls one after the other would not give. It must stay equal to
/// `rk4_step_leading`, operation for operation (the same stages, the same expressions in
/// the same order), so that a paired run is the run alone bit for bit; the test
/// `paired_runs_are_the_runs_alone_bit_for_bit` below checks it. (A generic `L`-lane step
/// shared by both passes that test, but its speed on the pair could not be shown equal.)
#[inline(always)]
fn rk4_step_pair<const N: usize, const M: usize>(
    (xa, ha): (&mut [f64; N], f64),
    mut da: impl FnMut(Rk4Stage, &[f64; N], &mut [f64; N]),
    (xb, hb): (&mut [f64; N], f64),
    mut db: impl FnMut(Rk4Stage, &[f64; N], &mut [f64; N]),
) {
    let (mut k1a, mut k2a, mut k3a, mut k4a) = ([0.0; N], [0.0; N], [0.0; N], [0.0; N]);
    let (mut k1b, mut k2b, mut k3b, mut k4b) = ([0.0; N], [0.0; N], [0.0; N], [0.0; N]);
    let (mut ata, mut atb) = (*xa, *xb);
    da(Rk4Stage::Start, xa, &mut k1a);
    db(Rk4Stage::Start, xb, &mut k1b);
    for j in 0..M {
        ata[j] = xa[j] + 0.5 * ha * k1a[j];
        atb[j] = xb[j] + 0.5 * hb * k1b[j];
    }
    da(Rk4Stage::Middle, &ata, &mut k2a);
    db(Rk4Stage::Middle, &atb, &mut k2b);
    for j in 0..M {
        ata[j] = xa[j] + 0.5 * ha * k2a[j];
        atb[j] = xb[j] + 0.5 * hb * k2b[j];
    }
    da(Rk4Stage::Middle, &ata, &mut k3a);
    db(Rk4Stage::Middle, &atb, &mut k3b);
    for j in 0..M {
        ata[j] = xa[j] + ha * k3a[j];
        atb[j] = xb[j] + hb * k3b[j];
    }
    da(Rk4Stage::End, &ata, &mut k4a);
    db(Rk4Stage::End, &atb, &mut k4b);
    for j in 0..M {
        xa[j] += ha / 6.0 * (k1a[j] + 2.0 * k2a[j] + 2.0 * k3a[j] + k4a[j]);
        xb[j] += hb / 6.0 * (k1b[j] + 2.0 * k2b[j] + 2.0 * k3b[j] + k4b[j]);
    }
}

/// The derivative of `model` at the stage's inputs, noise-free and without delay.
#[inline(always)]
fn derivative<'a>(
    model: &'a Model,
    inputs: &'a [Inputs; 3],
) -> impl FnMut(Rk4Stage, &State, &mut State) + 'a {
    #[inline(always)]
    move |stage, x, dx| {
        let inp = rk4_stage_inputs(&[&inputs[0], &inputs[1], &inputs[2]], stage);
        model.derivatives(x, inp, &SensorNoise::default(), 0.0, dx);
    }
}

/// Advance two pairable simulators by `dt_s`, each from its own `from` to its own `to`
/// inputs, noise-free: their common sub-steps together, the rest of either alone.
fn advance_pair(
    a: &mut Simulator,
    b: &mut Simulator,
    dt_s: f64,
    (from_a, to_a): (&Inputs, &Inputs),
    (from_b, to_b): (&Inputs, &Inputs),
) {
    let ia = a.interval(dt_s, from_a, to_a);
    let ib = b.interval(dt_s, from_b, to_b);
    let zero = SensorNoise::default();
    for i in 0..ia.n.max(ib.n) {
        match (i < ia.n, i < ib.n) {
            (true, true) => {
                let (sa, sb) = (ia.inputs(i), ib.inputs(i));
                rk4_step_pair::<NX, CORE_STATES>(
                    (&mut a.state, ia.h_s),
                    derivative(&a.model, &sa),
                    (&mut b.state, ib.h_s),
                    derivative(&b.model, &sb),
                );
                a.model.project(&mut a.state);
                b.model.project(&mut b.state);
                a.time_s = ia.end_time_s(i);
                b.time_s = ib.end_time_s(i);
            }
            (true, false) => a.substep(&ia, i, &zero),
            (false, true) => b.substep(&ib, i, &zero),
            (false, false) => {}
        }
    }
}

/// One run of a pair: its simulator, inputs, outputs so far and whether it stopped.
struct Lane<'a> {
    sim: Simulator,
    inputs: &'a [Inputs],
    out: Vec<Outputs>,
    stop: Option<Stop>,
}

impl<'a> Lane<'a> {
    fn new(model: &Model, inputs: &'a [Inputs], max_substep_s: f64, checks: Checks) -> Self {
        let mut sim = Simulator::new(model.clone(), 0.0, max_substep_s);
        sim.checks = checks;
        Lane {
            sim,
            inputs,
            out: Vec::with_capacity(inputs.len()),
            stop: None,
        }
    }

    /// Whether sample `k` is still to be read (the run has neither ended nor stopped).
    fn reads(&self, k: usize) -> bool {
        self.stop.is_none() && k < self.inputs.len()
    }

    /// Whether the run advances past sample `k`.
    fn advances(&self, k: usize) -> bool {
        self.stop.is_none() && k + 1 < self.inputs.len()
    }

    /// After the advance past sample `k`: exact sample time, and the stop when the run
    /// diverged (no later sample read), as [`super::simulate_record_with`] does.
    fn settle(&mut self, k: usize, dt_s: f64) {
        self.sim.time_s = (k + 1) as f64 * dt_s;
        if let Some(reason) = self.sim.diverged() {
            self.stop = Some(Stop {
                time_s: self.sim.time_s,
                reason,
            });
        }
    }

    /// The run padded to every sample ([`Run`]), as [`super::simulate_run_with`] gives it.
    fn run(self) -> Run {
        let samples = self.inputs.len();
        match self.stop {
            None => Ok(self.out),
            Some(Stop { time_s, reason }) => Err(Diverged {
                time_s,
                reason,
                outputs: self.out,
                samples,
            }),
        }
        .into()
    }
}

/// Two noise-free runs at the same sampling rate, each as [`super::simulate_run_with`]
/// gives it (bit for bit), advanced together where both are pairable.
pub fn simulate_run_pair(
    (model_a, inputs_a): (&Model, &[Inputs]),
    (model_b, inputs_b): (&Model, &[Inputs]),
    sample_rate_hz: f64,
    max_substep_s: f64,
    checks: Checks,
) -> [Run; 2] {
    let mut a = Lane::new(model_a, inputs_a, max_substep_s, checks);
    let mut b = Lane::new(model_b, inputs_b, max_substep_s, checks);
    let paired = a.sim.pairable() && b.sim.pairable();
    let dt = 1.0 / sample_rate_hz;
    let zero = SensorNoise::default();
    for k in 0..inputs_a.len().max(inputs_b.len()) {
        for lane in [&mut a, &mut b] {
            if lane.reads(k) {
                let o = lane.sim.outputs(&lane.inputs[k], &zero);
                lane.out.push(o);
            }
        }
        let (go_a, go_b) = (a.advances(k), b.advances(k));
        if paired && go_a && go_b {
            let step_a = (&inputs_a[k], &inputs_a[k + 1]);
            let step_b = (&inputs_b[k], &inputs_b[k + 1]);
            advance_pair(&mut a.sim, &mut b.sim, dt, step_a, step_b);
        } else {
            for (lane, go) in [(&mut a, go_a), (&mut b, go_b)] {
                if go {
                    lane.sim
                        .advance(dt, &lane.inputs[k], &lane.inputs[k + 1], &zero);
                }
            }
        }
        for (lane, go) in [(&mut a, go_a), (&mut b, go_b)] {
            if go {
                lane.settle(k, dt);
            }
        }
    }
    [a.run(), b.run()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Reference;
    use crate::params::{Params, ServovalveModel};
    use crate::solver::{simulate_run_with, DEFAULT_MAX_SUBSTEP_S};

    /// `n` samples at `fs` of a sine sweep of amplitude `amp_m` from rest.
    fn sweep(n: usize, fs: f64, amp_m: f64) -> Vec<Inputs> {
        (0..n)
            .map(|k| {
                let t = k as f64 / fs;
                let phase = 2.0 * std::f64::consts::PI * (0.5 + 1.5 * t) * t;
                let w = 2.0 * std::f64::consts::PI * (0.5 + 3.0 * t);
                Inputs {
                    reference: Reference {
                        displacement_m: amp_m * phase.sin(),
                        velocity_m_s: amp_m * w * phase.cos(),
                        acceleration_m_s2: -amp_m * w * w * phase.sin(),
                    },
                    external_force_n: 0.0,
                }
            })
            .collect()
    }

    /// Every output of a run as bits (NaN after a stop compares equal).
    fn bits(run: &Run) -> Vec<[u64; 8]> {
        run.outputs
            .iter()
            .map(|o| {
                [
                    o.valve_command,
                    o.spool_position,
                    o.displacement_m,
                    o.velocity_m_s,
                    o.acceleration_m_s2,
                    o.actuator_force_n,
                    o.pressure_a_pa,
                    o.pressure_b_pa,
                ]
                .map(f64::to_bits)
            })
            .collect()
    }

    /// Runs of different lengths, valves and gains, one that diverges and one that cannot
    /// be paired (a delay valve): each the same bit for bit as alone.
    #[test]
    fn paired_runs_are_the_runs_alone_bit_for_bit() {
        let fs = 512.0;
        let first = Params::trees_lab();
        let mut second = first;
        second.servovalve.model = ServovalveModel::SecondOrder;
        second.controller.kp *= 1.3;
        // a valve pole far beyond what the sub-steps may resolve: RK4 blows up
        let mut unstable = first;
        unstable.servovalve.model = ServovalveModel::FirstOrder;
        unstable.servovalve.time_constant_s = 1e-6;
        let mut delay = first;
        delay.servovalve.model = ServovalveModel::Delay;
        let (long, short) = (sweep(3000, fs, 0.05), sweep(2000, fs, 0.08));
        let checks = Checks::DivergenceOnly;
        let alone = |p: &Params, u: &[Inputs]| {
            simulate_run_with(&Model::new(p), u, fs, None, DEFAULT_MAX_SUBSTEP_S, checks)
        };
        for (pa, pb) in [(first, second), (unstable, second), (second, delay)] {
            let (ma, mb) = (Model::new(&pa), Model::new(&pb));
            let [ra, rb] = simulate_run_pair(
                (&ma, &long),
                (&mb, &short),
                fs,
                DEFAULT_MAX_SUBSTEP_S,
                checks,
            );
            for (paired, p, u) in [(ra, &pa, &long), (rb, &pb, &short)] {
                let single = alone(p, u);
                assert_eq!(paired.stop, single.stop);
                assert!(bits(&paired) == bits(&single), "{:?}", p.servovalve.model);
            }
        }
        assert!(
            alone(&unstable, &long).stop.is_some(),
            "the unstable run stops"
        );
    }
}
