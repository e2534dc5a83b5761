//! Small-signal analysis of the closed loop at rest (spec sections 2-7 linearised):
//! state-space matrices, closed-loop poles and the analytic transfer functions the paper
//! measures (table TF, command -> spool, spool -> force, acceleration -> force).
//!
//! The plant matrices are written analytically from the parameters (`plant.rs`: ideal
//! actuator, eq. of spec section 4; Bouc-Wen linearised at `Z = 0`: `Z' = v/Y`,
//! `F_D = F_mu Z`). [`jacobian_at_rest`] (`jacobian.rs`) differentiates the simulator's own
//! derivative function instead, which is how the tests show that the nonlinear actuator
//! linearises to the ideal one. The servovalve enters as its transfer function (`valve.rs`),
//! so the `delay` variant is the exact `Ks exp(-s tau)` in every FRF; its closed-loop poles
//! use a Pade approximant. `figures.rs`: sampled responses and their peak and phase figures.
//!
//! `flow_saturation` and `valve_deadband` are amplitude nonlinearities with no
//! small-signal meaning at rest; [`Linearisation::notes`] says so when they are enabled.
//! Each specimen mode adds its oscillator (spec section 7, second part). `free_play` with
//! no gap is linearised with its contact engaged; with a gap the rod rests inside it
//! where the small-signal model is not defined, and rod and table are joined rigidly.

mod figures;
mod jacobian;
mod plant;
mod valve;

pub use figures::{linear_grid, log_grid, unwrapped_phase, Frf, TfFigures};
pub use jacobian::{jacobian_at_rest, LinearError};
pub use plant::{engaged_free_play, Plant};
pub use valve::ValveTf;

use crate::params::{ActuatorModel, Params};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Order of the Pade approximant of the delay valve used for closed-loop poles.
pub const PADE_ORDER: usize = 4;
/// Frequency at which the "low-frequency gain" of a table TF is read, Hz.
pub const LOW_FREQUENCY_HZ: f64 = 0.5;

/// Rows of [`Plant::c`]: what the controller measures (spec section 2).
pub mod meas {
    /// LVDT displacement `x - x_f`.
    pub const DISPLACEMENT: usize = 0;
    /// Relative velocity `v - v_f`.
    pub const VELOCITY: usize = 1;
    /// Absolute table acceleration.
    pub const ACCELERATION: usize = 2;
    /// Actuator force `A P_L`.
    pub const FORCE: usize = 3;
}

/// The linearised closed loop: plant, valve and controller gains.
#[derive(Debug, Clone)]
pub struct Linearisation {
    pub plant: Plant,
    pub valve: ValveTf,
    /// Feedback gains on the measurement rows `[Kp, Kv, Ka, Kdp]`.
    pub feedback: [f64; 4],
    /// Reference gains on `[r, r', r'']`: `[Kp, Kv + Fv, Ka + Fa]`.
    pub reference: [f64; 3],
    /// Effects left out of the small-signal model, in words.
    pub notes: Vec<String>,
}

fn jw(f_hz: f64) -> Complex64 {
    Complex64::new(0.0, 2.0 * PI * f_hz)
}

impl Linearisation {
    pub fn new(p: &Params) -> Linearisation {
        let k = &p.controller;
        let mut notes = Vec::new();
        if p.flow_saturation.enabled {
            notes.push(
                "flow_saturation is an amplitude limit: not in the small-signal model".into(),
            );
        }
        if p.valve_deadband.enabled {
            notes.push(
                "valve_deadband: at rest the flow gain is zero; the small-signal model uses the flow gain outside the band".into(),
            );
        }
        if p.free_play.enabled {
            notes.push(if engaged_free_play(p) {
                "free_play with no gap: the contact is linearised as engaged (a spring and damper between rod and table)".into()
            } else {
                "free_play: at rest the rod sits inside the gap, where the linearisation is not defined; the small-signal model joins rod and table rigidly (the baseline's moving mass M)".into()
            });
        }
        if p.actuator.model == ActuatorModel::Nonlinear {
            notes.push("nonlinear actuator linearised at rest: identical to the ideal one (spec section 4)".into());
        }
        Linearisation {
            plant: Plant::new(p),
            valve: ValveTf::new(p),
            feedback: [k.kp, k.kv, k.ka, k.kdp],
            reference: [k.kp, k.kv + k.fv, k.ka + k.fa],
            notes,
        }
    }

    /// The feedback row `K C` over the plant state.
    fn feedback_row(&self) -> DVector<f64> {
        let mut row = DVector::zeros(self.plant.order());
        for (i, g) in self.feedback.iter().enumerate() {
            row += self.plant.c.row(i).transpose() * *g;
        }
        row
    }

    /// Closed-loop plant states per unit reference displacement at `s`
    /// (reference velocity `s R`, acceleration `s^2 R`).
    fn closed_loop_states(&self, s: Complex64) -> Option<DVector<Complex64>> {
        let n = self.plant.order();
        let g = self.valve.response(s);
        let kc = self.feedback_row();
        let b = &self.plant.b_spool;
        // (sI - A + G b K C) X = b G k_r(s) R
        let m = DMatrix::from_fn(n, n, |i, j| {
            let d = if i == j { s } else { Complex64::new(0.0, 0.0) };
            d - self.plant.a[(i, j)] + g * b[i] * kc[j]
        });
        let kr = self.reference[0] + self.reference[1] * s + self.reference[2] * s * s;
        let rhs = b.map(|x| g * kr * x);
        m.lu().solve(&rhs)
    }

    fn closed_loop_row(&self, row: usize, s: Complex64) -> Complex64 {
        match self.closed_loop_states(s) {
            Some(x) => (0..self.plant.order())
                .map(|j| self.plant.c[(row, j)] * x[j])
                .sum(),
            None => Complex64::new(f64::NAN, f64::NAN),
        }
    }

    /// The table TF: reference acceleration -> absolute table acceleration at `f_hz`.
    pub fn table_tf(&self, f_hz: f64) -> Complex64 {
        let s = jw(f_hz);
        self.closed_loop_row(meas::ACCELERATION, s) / (s * s)
    }

    /// Reference displacement -> LVDT (relative) displacement at `f_hz`.
    pub fn displacement_tf(&self, f_hz: f64) -> Complex64 {
        self.closed_loop_row(meas::DISPLACEMENT, jw(f_hz))
    }

    /// Command -> spool (the servovalve alone, paper 4.1.1).
    pub fn command_to_spool(&self, f_hz: f64) -> Complex64 {
        self.valve.response(jw(f_hz))
    }

    /// Spool -> actuator force (the oil column on the table, paper 4.1.3), N per unit spool.
    pub fn spool_to_force(&self, f_hz: f64) -> Complex64 {
        self.plant.spool_to(meas::FORCE, jw(f_hz))
    }

    /// Table acceleration -> actuator force (apparent mass, paper 4.1.2), kg.
    pub fn acceleration_to_force(&self, f_hz: f64) -> Complex64 {
        let s = jw(f_hz);
        self.plant.spool_to(meas::FORCE, s) / self.plant.spool_to(meas::ACCELERATION, s)
    }

    /// Closed-loop state matrix `(A_cl, B_cl)` over `[valve states, plant states]` with
    /// inputs `[r, r', r'']` (the delay valve as a Pade approximant).
    pub fn closed_loop_matrices(&self) -> (DMatrix<f64>, DMatrix<f64>) {
        let (av, bv, cv, dv) = self.valve.state_space();
        let nv = av.nrows();
        let np = self.plant.order();
        let kc = self.feedback_row();
        let b = &self.plant.b_spool;
        let mut a = DMatrix::zeros(nv + np, nv + np);
        a.view_mut((0, 0), (nv, nv)).copy_from(&av);
        a.view_mut((0, nv), (nv, np))
            .copy_from(&(-&bv * kc.transpose()));
        a.view_mut((nv, 0), (np, nv))
            .copy_from(&(b * cv.transpose()));
        a.view_mut((nv, nv), (np, np))
            .copy_from(&(&self.plant.a - b * kc.transpose() * dv));
        let mut bin = DMatrix::zeros(nv + np, 3);
        for (j, kr) in self.reference.iter().enumerate() {
            for i in 0..nv {
                bin[(i, j)] = bv[i] * kr;
            }
            for i in 0..np {
                bin[(nv + i, j)] = b[i] * dv * kr;
            }
        }
        (a, bin)
    }

    /// Closed-loop poles, sorted by frequency (rad/s); `None` when they cannot be
    /// computed: a non-finite entry in the state matrix (parameters nobody validated) or
    /// an eigenvalue iteration that does not converge. nalgebra's plain
    /// `complex_eigenvalues` iterates without a limit and never returns on such a matrix.
    pub fn poles(&self) -> Option<Vec<Complex64>> {
        let (a, _) = self.closed_loop_matrices();
        if !a.iter().all(|x| x.is_finite()) {
            return None;
        }
        let schur = nalgebra::Schur::try_new(a, f64::EPSILON, POLE_ITERATION_LIMIT)?;
        let mut p: Vec<Complex64> = schur.complex_eigenvalues().iter().copied().collect();
        if !p.iter().all(|q| q.re.is_finite() && q.im.is_finite()) {
            return None;
        }
        p.sort_by(|x, y| x.norm().total_cmp(&y.norm()).then(x.im.total_cmp(&y.im)));
        Some(p)
    }

    /// Sample `tf` on a grid.
    pub fn sample(&self, grid_hz: &[f64], tf: impl Fn(&Self, f64) -> Complex64) -> Frf {
        Frf {
            frequency_hz: grid_hz.to_vec(),
            response: grid_hz.iter().map(|&f| tf(self, f)).collect(),
        }
    }

    /// Figures of the table TF on a fine grid (0.005 Hz from 0.5 to 50 Hz).
    pub fn table_tf_figures(&self) -> Option<TfFigures> {
        let grid = linear_grid(LOW_FREQUENCY_HZ, 50.0, 0.005);
        TfFigures::from_frf(&self.sample(&grid, Self::table_tf))
    }
}

/// A closed-loop pole with a positive real part counts as unstable once its real part
/// exceeds this fraction of its magnitude (or of 1 rad/s near the origin): the
/// eigenvalue solver's round-off on a marginal pole at zero (no displacement feedback)
/// is about 1e-12 of the matrix norm, and a growth this slow (1e-9 of the frequency)
/// would take longer than any test to show.
pub const UNSTABLE_REAL_PART: f64 = 1e-9;

/// Most QR sweeps of the pole computation: the Francis iteration takes a few sweeps per
/// eigenvalue, and the closed loop has at most about 15 states, so a thousand is two
/// orders of magnitude of margin and still returns in well under a millisecond.
const POLE_ITERATION_LIMIT: usize = 1000;

/// A closed-loop pole in the figures a user reads.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Pole {
    pub frequency_hz: f64,
    /// `-Re / |p|`: negative for a growing oscillation.
    pub damping_ratio: f64,
    pub re: f64,
    pub im: f64,
}

impl Pole {
    fn of(q: Complex64) -> Pole {
        Pole {
            frequency_hz: q.norm() / (2.0 * PI),
            damping_ratio: if q.norm() > 0.0 {
                -q.re / q.norm()
            } else {
                1.0
            },
            re: q.re,
            im: q.im,
        }
    }
}

impl Linearisation {
    /// The closed-loop poles with `Im >= 0` (one of each conjugate pair), as [`Pole`]s;
    /// `None` as for [`Linearisation::poles`].
    pub fn upper_poles(&self) -> Option<Vec<Pole>> {
        let poles = self.poles()?;
        Some(
            poles
                .into_iter()
                .filter(|q| q.im >= 0.0)
                .map(Pole::of)
                .collect(),
        )
    }

    /// The poles of [`Linearisation::upper_poles`] with a positive real part (spec
    /// section 8): the loop at rest is unstable. `None` as for [`Linearisation::poles`].
    pub fn unstable_poles(&self) -> Option<Vec<Pole>> {
        let mut poles = self.upper_poles()?;
        poles.retain(|q| q.re > UNSTABLE_REAL_PART * q.re.hypot(q.im).max(1.0));
        Some(poles)
    }
}

/// The warning every command that computes or simulates with `p` prints (spec section
/// 8): `None` when the closed loop at rest is stable.
pub fn stability_warning(p: &Params) -> Option<String> {
    let Some(unstable) = Linearisation::new(p).unstable_poles() else {
        return Some(
            "the closed-loop poles could not be computed from these parameters (a \
             non-finite value, or an eigenvalue iteration that did not converge), so \
             whether the loop at rest is stable is unknown"
                .to_string(),
        );
    };
    let worst = unstable.iter().max_by(|a, b| a.re.total_cmp(&b.re))?;
    Some(format!(
        "the closed loop is unstable at rest: {} pole(s) with a positive real part, \
         the fastest-growing at {:.3} Hz with damping ratio {:.4} (pole {:.4} {:+.4}i \
         rad/s); a run will grow until it leaves the operating limits",
        unstable.len(),
        worst.frequency_hz,
        worst.damping_ratio,
        worst.re,
        worst.im
    ))
}

/// Oil-column figures of spec section 4: `k_oil = 4 beta A^2 / V_t`,
/// `f_oil = sqrt(k_oil / M) / 2 pi`, `zeta_oil = (C_l / A) sqrt(beta M / V_t)`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OilColumn {
    pub stiffness_n_m: f64,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
}

impl OilColumn {
    pub fn of(p: &Params) -> OilColumn {
        let a = &p.actuator;
        let k = a.oil_column_stiffness_n_m();
        OilColumn {
            stiffness_n_m: k,
            frequency_hz: (k / p.table.mass_kg).sqrt() / (2.0 * PI),
            damping_ratio: a.oil_column_damping_ratio(p.table.mass_kg),
        }
    }
}
