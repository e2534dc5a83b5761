//! The numerical linearisation: central differences of the simulator's own derivative
//! function at rest (how the tests show the nonlinear actuator linearises to the ideal
//! one).

use crate::model::{ix, Inputs, Model, Reference, SensorNoise, NX};
use crate::params::{ActuatorModel, ServovalveModel};
use nalgebra::{DMatrix, DVector};

/// Errors of the numerical linearisation.
#[derive(Debug, thiserror::Error)]
pub enum LinearError {
    #[error(
        "the delay servovalve has no finite state: linearise with a first- or second-order valve"
    )]
    DelayValve,
    #[error(
        "free play switches at rest (its contact engages there), so the derivative function \
         has no Jacobian there; the analytic plant linearises it (spec section 7)"
    )]
    FreePlay,
}

/// Central-difference Jacobian of the simulator's derivative function at rest, in the
/// coordinates of [`Linearisation::closed_loop_matrices`]: `[valve states, P_L, x, v, Z,
/// (x_s, v_s) per specimen mode, (x_f, v_f)]`, inputs `[r, r', r'']`. For the nonlinear actuator the load
/// pressure direction is `(P_a, P_b) += (+d/2, -d/2)` and its rate `P_a' - P_b'`.
pub fn jacobian_at_rest(model: &Model) -> Result<(DMatrix<f64>, DMatrix<f64>), LinearError> {
    let p = &model.params;
    let nonlinear = p.actuator.model == ActuatorModel::Nonlinear;
    let at_rest = AtRest {
        model,
        dirs: reduced_coordinates(model, nonlinear)?,
        nonlinear,
        rest: model.rest_state(),
        noise: SensorNoise::default(),
    };
    Ok((at_rest.state_jacobian(), at_rest.reference_jacobian()))
}

/// One reduced coordinate: its direction in the full state and its difference step.
type Direction = ([f64; NX], f64);

/// The unit direction of full state `i`.
fn unit(i: usize) -> [f64; NX] {
    let mut d = [0.0; NX];
    d[i] = 1.0;
    d
}

/// The reduced coordinates in their order, each with its step: the servovalve's states,
/// the load pressure, the table and friction, each specimen mode, the foundation. The
/// delay valve and free play have no Jacobian at rest.
fn reduced_coordinates(model: &Model, nonlinear: bool) -> Result<Vec<Direction>, LinearError> {
    let p = &model.params;
    let mut dirs: Vec<Direction> = Vec::new();
    match p.servovalve.model {
        ServovalveModel::Delay => return Err(LinearError::DelayValve),
        _ if p.free_play.enabled => return Err(LinearError::FreePlay),
        ServovalveModel::FirstOrder => dirs.push((unit(ix::XV), 1e-6)),
        ServovalveModel::SecondOrder => {
            dirs.push((unit(ix::XV), 1e-6));
            dirs.push((unit(ix::XV_DOT), 1e-4));
        }
    }
    let mut load = [0.0; NX];
    if nonlinear {
        load[ix::PA] = 0.5;
        load[ix::PB] = -0.5;
    } else {
        load[ix::PA] = 1.0;
    }
    dirs.push((load, 1e3));
    dirs.push((unit(ix::X), 1e-7));
    dirs.push((unit(ix::V), 1e-7));
    dirs.push((unit(ix::Z), 1e-6));
    if p.specimen.enabled {
        let present = p.specimen.modes().len();
        for &(xs, vs) in &ix::SPECIMEN_MODES[..present] {
            dirs.push((unit(xs), 1e-7));
            dirs.push((unit(vs), 1e-7));
        }
    }
    if p.foundation.enabled {
        dirs.push((unit(ix::XF), 1e-7));
        dirs.push((unit(ix::VF), 1e-7));
    }
    Ok(dirs)
}

/// The simulator at rest, differentiated along the reduced coordinates `dirs` (without
/// sensor noise).
struct AtRest<'a> {
    model: &'a Model,
    dirs: Vec<Direction>,
    nonlinear: bool,
    rest: [f64; NX],
    noise: SensorNoise,
}

impl AtRest<'_> {
    /// Project a full-state derivative onto the reduced coordinates (the nonlinear
    /// actuator's load pressure rate is `P_a' - P_b'`).
    fn reduce(&self, ds: &[f64; NX]) -> DVector<f64> {
        let v: Vec<f64> = self
            .dirs
            .iter()
            .map(|(d, _)| {
                if d[ix::PA] != 0.0 && self.nonlinear {
                    ds[ix::PA] - ds[ix::PB]
                } else {
                    let i = d.iter().position(|&x| x != 0.0).unwrap_or(0);
                    ds[i]
                }
            })
            .collect();
        DVector::from_vec(v)
    }

    /// The reduced derivative at state `s` with inputs `inp`.
    fn eval(&self, s: &[f64; NX], inp: &Inputs) -> DVector<f64> {
        let mut ds = [0.0; NX];
        self.model.derivatives(s, inp, &self.noise, 0.0, &mut ds);
        self.reduce(&ds)
    }

    /// `A`: one central difference along each reduced coordinate, inputs zero.
    fn state_jacobian(&self) -> DMatrix<f64> {
        let n = self.dirs.len();
        let zero = Inputs::default();
        let mut a = DMatrix::zeros(n, n);
        for (j, (d, h)) in self.dirs.iter().enumerate() {
            let mut sp = self.rest;
            let mut sm = self.rest;
            for i in 0..NX {
                sp[i] += h * d[i];
                sm[i] -= h * d[i];
            }
            let col = (self.eval(&sp, &zero) - self.eval(&sm, &zero)) / (2.0 * h);
            a.set_column(j, &col);
        }
        a
    }

    /// `B`: one central difference along each reference channel `r, r', r''` at rest.
    fn reference_jacobian(&self) -> DMatrix<f64> {
        let mut b = DMatrix::zeros(self.dirs.len(), 3);
        let steps = [1e-7, 1e-7, 1e-6];
        for (j, h) in steps.iter().enumerate() {
            let mk = |sign: f64| {
                let mut r = Reference::default();
                match j {
                    0 => r.displacement_m = sign * h,
                    1 => r.velocity_m_s = sign * h,
                    _ => r.acceleration_m_s2 = sign * h,
                }
                Inputs {
                    reference: r,
                    external_force_n: 0.0,
                }
            };
            let col =
                (self.eval(&self.rest, &mk(1.0)) - self.eval(&self.rest, &mk(-1.0))) / (2.0 * h);
            b.set_column(j, &col);
        }
        b
    }
}
