//! Small-signal analysis of the closed loop at rest (spec sections 2-7 linearised):
//! state-space matrices, closed-loop poles and the analytic transfer functions the paper
//! measures (table TF, command -> spool, spool -> force, acceleration -> force).
//!
//! The plant matrices are written analytically from the parameters (ideal actuator,
//! eq. of spec section 4; Bouc-Wen linearised at `Z = 0`: `Z' = v/Y`, `F_D = F_mu Z`).
//! [`jacobian_at_rest`] differentiates the simulator's own derivative function instead,
//! which is how the tests show that the nonlinear actuator linearises to the ideal one.
//! The servovalve enters as its transfer function, so the `delay` variant is the exact
//! `Ks exp(-s tau)` in every FRF; its closed-loop poles use a Pade approximant.
//!
//! `flow_saturation` and `valve_deadband` are amplitude nonlinearities with no
//! small-signal meaning at rest; [`Linearisation::notes`] says so when they are enabled.
//! Each specimen mode adds its oscillator (spec section 7, second part). `free_play` with
//! no gap is linearised with its contact engaged; with a gap the rod rests inside it
//! where the small-signal model is not defined, and rod and table are joined rigidly.

use crate::model::{ix, Inputs, Model, Reference, SensorNoise, NX};
use crate::params::{ActuatorModel, Params, ServovalveModel};
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

/// The open-loop plant from spool position (and external force) to the measurements:
/// `X' = a X + b_spool x_v + b_external F_ext`, `y = c X`.
/// States (enabled blocks only): `P_L, x, v, Z`, then `x_s, v_s` of each specimen mode,
/// then `x_f, v_f` (foundation), then `x_r, v_r` (free-play rod with no gap).
#[derive(Debug, Clone)]
pub struct Plant {
    pub a: DMatrix<f64>,
    pub b_spool: DVector<f64>,
    pub b_external: DVector<f64>,
    pub c: DMatrix<f64>,
    pub names: Vec<&'static str>,
}

/// The servovalve as a transfer function from command to spool (spec section 3).
#[derive(Debug, Clone, Copy)]
pub enum ValveTf {
    Delay {
        gain: f64,
        tau_s: f64,
    },
    FirstOrder {
        gain: f64,
        tau_s: f64,
    },
    SecondOrder {
        gain: f64,
        omega_rad_s: f64,
        damping_ratio: f64,
    },
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

/// Peak and phase figures of a table transfer function (spec section 6).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TfFigures {
    pub peak_hz: f64,
    pub peak_gain: f64,
    pub low_frequency_gain: f64,
    /// `peak_gain / low_frequency_gain`.
    pub peak_ratio: f64,
    /// Phase at `peak - 1 Hz` minus phase at `peak + 1 Hz`, degrees (unwrapped).
    pub phase_drop_deg: f64,
    /// Where the phase falls fastest within +-1 Hz of the peak, Hz.
    pub steepest_hz: f64,
}

/// A sampled frequency response.
#[derive(Debug, Clone, Default)]
pub struct Frf {
    pub frequency_hz: Vec<f64>,
    pub response: Vec<Complex64>,
}

impl ValveTf {
    /// The servovalve of parameter set `p`.
    pub fn new(p: &Params) -> Self {
        let v = &p.servovalve;
        match v.model {
            ServovalveModel::Delay => ValveTf::Delay {
                gain: v.gain,
                tau_s: v.time_constant_s,
            },
            ServovalveModel::FirstOrder => ValveTf::first_order(v.gain, v.time_constant_s),
            ServovalveModel::SecondOrder => {
                ValveTf::second_order(v.gain, v.natural_frequency_hz, v.damping_ratio)
            }
        }
    }

    /// The first-order valve of paper eq. 4.1, `Ks / (1 + s tau)`.
    pub fn first_order(gain: f64, tau_s: f64) -> Self {
        ValveTf::FirstOrder { gain, tau_s }
    }

    /// The second-order valve of paper eq. 4.2, `Ks w^2 / (s^2 + 2 xi w s + w^2)`, with
    /// `w = 2 pi natural_frequency_hz`.
    pub fn second_order(gain: f64, natural_frequency_hz: f64, damping_ratio: f64) -> Self {
        ValveTf::SecondOrder {
            gain,
            omega_rad_s: 2.0 * PI * natural_frequency_hz,
            damping_ratio,
        }
    }

    /// `x_v(s) / u(s)`.
    pub fn response(&self, s: Complex64) -> Complex64 {
        match *self {
            ValveTf::Delay { gain, tau_s } => gain * (-s * tau_s).exp(),
            ValveTf::FirstOrder { gain, tau_s } => gain / (1.0 + s * tau_s),
            ValveTf::SecondOrder {
                gain,
                omega_rad_s: w,
                damping_ratio: xi,
            } => gain * w * w / (s * s + 2.0 * xi * w * s + w * w),
        }
    }

    /// A state-space realisation `(A, B, C, D)`; the delay as a Pade approximant of
    /// order [`PADE_ORDER`] (controllable canonical form).
    pub fn state_space(&self) -> (DMatrix<f64>, DVector<f64>, DVector<f64>, f64) {
        match *self {
            ValveTf::FirstOrder { gain, tau_s } => (
                DMatrix::from_element(1, 1, -1.0 / tau_s),
                DVector::from_element(1, gain / tau_s),
                DVector::from_element(1, 1.0),
                0.0,
            ),
            ValveTf::SecondOrder {
                gain,
                omega_rad_s: w,
                damping_ratio: xi,
            } => (
                DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -w * w, -2.0 * xi * w]),
                DVector::from_row_slice(&[0.0, w * w * gain]),
                DVector::from_row_slice(&[1.0, 0.0]),
                0.0,
            ),
            ValveTf::Delay { gain, tau_s } => pade_delay(gain, tau_s, PADE_ORDER),
        }
    }
}

/// `gain exp(-s tau)` as the diagonal Pade approximant of order `n` in `sigma = s tau`
/// (so the companion matrix stays well conditioned): `N(sigma)/D(sigma)` with
/// `D = sum c_k sigma^k`, `N = sum (-1)^k c_k sigma^k`, `c_k = (2n-k)! n! / ((2n)! k! (n-k)!)`.
fn pade_delay(gain: f64, tau_s: f64, n: usize) -> (DMatrix<f64>, DVector<f64>, DVector<f64>, f64) {
    let fact = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
    let c: Vec<f64> = (0..=n)
        .map(|k| fact(2 * n - k) * fact(n) / (fact(2 * n) * fact(k) * fact(n - k)))
        .collect();
    // monic denominator in sigma
    let den: Vec<f64> = c.iter().map(|x| x / c[n]).collect();
    let num: Vec<f64> = (0..=n)
        .map(|k| gain * if k % 2 == 0 { den[k] } else { -den[k] })
        .collect();
    let d = num[n];
    // controllable canonical form in sigma; d/dt = (1/tau) d/dsigma-time
    let mut a = DMatrix::zeros(n, n);
    for i in 0..n - 1 {
        a[(i, i + 1)] = 1.0 / tau_s;
    }
    for k in 0..n {
        a[(n - 1, k)] = -den[k] / tau_s;
    }
    let mut b = DVector::zeros(n);
    b[n - 1] = 1.0 / tau_s;
    let cvec = DVector::from_iterator(n, (0..n).map(|k| num[k] - d * den[k]));
    (a, b, cvec, d)
}

impl Plant {
    /// The analytic plant at rest (spec sections 4, 5 and 7).
    pub fn new(p: &Params) -> Plant {
        let act = &p.actuator;
        let m = p.table.mass_kg;
        let area = act.piston_area_m2;
        let rate = 4.0 * act.bulk_modulus_pa / act.total_oil_volume_m3;
        // stick-slip: the amplitude at zero velocity is r_s F_mu
        let friction = p.friction.force_n
            * if p.stick_slip.enabled {
                p.stick_slip.static_ratio
            } else {
                1.0
            };
        let mut names = vec!["pressure_load", "table_x", "table_v", "friction_z"];
        // one (x, v) pair per present specimen mode: (mode, first state index)
        let mut modes = Vec::new();
        for (k, mode) in p.specimen.modes().into_iter().enumerate() {
            if p.specimen.enabled {
                modes.push((mode, names.len()));
                names.extend(SPECIMEN_STATE_NAMES[k]);
            }
        }
        let fnd = p.foundation.enabled.then(|| names.len());
        if fnd.is_some() {
            names.extend(["foundation_x", "foundation_v"]);
        }
        // free play: the contact linearised as engaged when the gap is 0; with a gap the
        // rod rests inside it and the small-signal model joins rod and table rigidly
        let rod = engaged_free_play(p).then(|| names.len());
        if rod.is_some() {
            names.extend(["rod_x", "rod_v"]);
        }
        let n = names.len();
        let (pl, x, v, z) = (0, 1, 2, 3);
        // the relative stroke `x - x_f` and its rate as rows over the state
        let mut rel_x = DVector::zeros(n);
        let mut rel_v = DVector::zeros(n);
        rel_x[x] = 1.0;
        rel_v[v] = 1.0;
        if let Some(f) = fnd {
            rel_x[f] = -1.0;
            rel_v[f + 1] = -1.0;
        }
        // force between table and reaction mass: F_A - F_D - F_E
        let mut stroke_force = DVector::zeros(n);
        stroke_force[pl] = area;
        stroke_force[z] = -friction;
        stroke_force -= &rel_x * p.table.stiffness_n_m;
        // net force on the table (spec section 5)
        let mut table_force = stroke_force.clone();
        let mut a = DMatrix::zeros(n, n);
        for (mode, s) in modes {
            let w = 2.0 * PI * mode.frequency_hz;
            let ks = mode.mass_kg * w * w;
            let cs = 2.0 * mode.damping_ratio * mode.mass_kg * w;
            // spring-damper force on the specimen: -k_s (x_s - x) - c_s (v_s - v)
            let mut on_specimen = DVector::zeros(n);
            on_specimen[s] = -ks;
            on_specimen[x] = ks;
            on_specimen[s + 1] = -cs;
            on_specimen[v] = cs;
            table_force -= &on_specimen;
            a[(s, s + 1)] = 1.0;
            a.set_row(s + 1, &(on_specimen / mode.mass_kg).transpose());
        }
        if let Some(f) = fnd {
            let w = 2.0 * PI * p.foundation.frequency_hz;
            let mf = p.foundation.mass_kg;
            let mut row = -&stroke_force;
            row[f] -= mf * w * w;
            row[f + 1] -= 2.0 * p.foundation.damping_ratio * mf * w;
            a[(f, f + 1)] = 1.0;
            a.set_row(f + 1, &(row / mf).transpose());
        }
        // the LVDT and the flow follow the piston: the rod's with engaged free play
        let (mut lvdt_x, mut lvdt_v) = (rel_x.clone(), rel_v.clone());
        let mut table_mass = m;
        if let Some(r) = rod {
            let rows = RodRows { x, v, pl, r, area };
            table_mass = rows.add(p, &mut a, &mut table_force, &mut lvdt_x, &mut lvdt_v);
        }
        let accel = &table_force / table_mass;
        // flow continuity (spec section 4, ideal form)
        let mut pl_row = -&lvdt_v * (rate * area);
        pl_row[pl] -= rate * act.leakage_m3_s_pa;
        a.set_row(pl, &pl_row.transpose());
        a[(x, v)] = 1.0;
        a.set_row(v, &accel.transpose());
        // Bouc-Wen at Z = 0 (eq. 4.15): Z' = v_rel / Y
        a.set_row(z, &(&rel_v / p.friction.yield_displacement_m).transpose());
        let mut b_spool = DVector::zeros(n);
        b_spool[pl] = rate * act.flow_gain_m3_s;
        let mut b_external = DVector::zeros(n);
        b_external[v] = 1.0 / table_mass;
        let mut c = DMatrix::zeros(4, n);
        c.set_row(meas::DISPLACEMENT, &lvdt_x.transpose());
        c.set_row(meas::VELOCITY, &lvdt_v.transpose());
        c.set_row(meas::ACCELERATION, &accel.transpose());
        c[(meas::FORCE, pl)] = area;
        Plant {
            a,
            b_spool,
            b_external,
            c,
            names,
        }
    }

    pub fn order(&self) -> usize {
        self.a.nrows()
    }

    /// `(sI - a)^-1 b_spool`: the state response to a unit spool.
    fn spool_response(&self, s: Complex64) -> Option<DVector<Complex64>> {
        let n = self.order();
        let m = DMatrix::from_fn(n, n, |i, j| {
            let d = if i == j { s } else { Complex64::new(0.0, 0.0) };
            d - self.a[(i, j)]
        });
        let rhs = self.b_spool.map(|x| Complex64::new(x, 0.0));
        m.lu().solve(&rhs)
    }

    /// Measurement row `row` per unit spool at `s`.
    pub fn spool_to(&self, row: usize, s: Complex64) -> Complex64 {
        match self.spool_response(s) {
            Some(x) => (0..self.order()).map(|j| self.c[(row, j)] * x[j]).sum(),
            None => Complex64::new(f64::NAN, f64::NAN),
        }
    }
}

/// Where the engaged free-play rod sits in the plant (spec section 7, second part): the
/// table's position and velocity, the load pressure, the rod's first state, piston area.
struct RodRows {
    x: usize,
    v: usize,
    pl: usize,
    r: usize,
    area: f64,
}

impl RodRows {
    /// Add the rod on its contact `k_c (x_r - x) + c_c (v_r - v)`: the actuator force
    /// drives the rod, the contact the table; the LVDT rows read the rod. Returns the
    /// table's own mass `M - m_r`.
    fn add(
        &self,
        p: &Params,
        a: &mut DMatrix<f64>,
        table_force: &mut DVector<f64>,
        lvdt_x: &mut DVector<f64>,
        lvdt_v: &mut DVector<f64>,
    ) -> f64 {
        let (x, v, r) = (self.x, self.v, self.r);
        let c = p.free_play.contact();
        let mut contact = DVector::zeros(a.nrows());
        contact[r] = c.stiffness_n_m;
        contact[x] = -c.stiffness_n_m;
        contact[r + 1] = c.damping_n_s_m;
        contact[v] = -c.damping_n_s_m;
        table_force[self.pl] -= self.area;
        *table_force += &contact;
        let mut rod_force = -contact;
        rod_force[self.pl] += self.area;
        a[(r, r + 1)] = 1.0;
        a.set_row(r + 1, &(rod_force / c.rod_mass_kg).transpose());
        lvdt_x[x] = 0.0;
        lvdt_x[r] = 1.0;
        lvdt_v[v] = 0.0;
        lvdt_v[r + 1] = 1.0;
        p.table.mass_kg - c.rod_mass_kg
    }
}

/// State names of the specimen's modes in [`Plant::names`], mode 1 first.
const SPECIMEN_STATE_NAMES: [[&str; 2]; 3] = [
    ["specimen_x", "specimen_v"],
    ["specimen2_x", "specimen2_v"],
    ["specimen3_x", "specimen3_v"],
];

/// Whether the plant holds the free-play rod: the effect on with no gap, so the contact
/// is engaged at rest (spec section 7; with a gap the linearisation at rest is not
/// defined and rod and table are joined rigidly, see [`Linearisation::notes`]).
pub fn engaged_free_play(p: &Params) -> bool {
    p.free_play.enabled && p.free_play.gap_m == 0.0
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

    /// Closed-loop poles, sorted by frequency (rad/s).
    pub fn poles(&self) -> Vec<Complex64> {
        let (a, _) = self.closed_loop_matrices();
        let mut p: Vec<Complex64> = a.complex_eigenvalues().iter().copied().collect();
        p.sort_by(|x, y| x.norm().total_cmp(&y.norm()).then(x.im.total_cmp(&y.im)));
        p
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
    /// The closed-loop poles with `Im >= 0` (one of each conjugate pair), as [`Pole`]s.
    pub fn upper_poles(&self) -> Vec<Pole> {
        self.poles()
            .into_iter()
            .filter(|q| q.im >= 0.0)
            .map(Pole::of)
            .collect()
    }

    /// The poles of [`Linearisation::upper_poles`] with a positive real part (spec
    /// section 8): the loop at rest is unstable.
    pub fn unstable_poles(&self) -> Vec<Pole> {
        self.upper_poles()
            .into_iter()
            .filter(|q| q.re > UNSTABLE_REAL_PART * q.re.hypot(q.im).max(1.0))
            .collect()
    }
}

/// The warning every command that computes or simulates with `p` prints (spec section
/// 8): `None` when the closed loop at rest is stable.
pub fn stability_warning(p: &Params) -> Option<String> {
    let unstable = Linearisation::new(p).unstable_poles();
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

/// `start, start + step, ... <= stop`.
pub fn linear_grid(start: f64, stop: f64, step: f64) -> Vec<f64> {
    let n = ((stop - start) / step + 1e-9).floor() as usize + 1;
    (0..n).map(|i| start + i as f64 * step).collect()
}

/// `n` points logarithmically spaced from `start` to `stop`.
pub fn log_grid(start: f64, stop: f64, n: usize) -> Vec<f64> {
    let (l0, l1) = (start.ln(), stop.ln());
    (0..n)
        .map(|i| (l0 + (l1 - l0) * i as f64 / (n.max(2) - 1) as f64).exp())
        .collect()
}

/// Unwrapped phase in radians.
pub fn unwrapped_phase(h: &[Complex64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(h.len());
    let mut offset = 0.0;
    let mut prev: Option<f64> = None;
    for z in h {
        let p = z.arg();
        if let Some(q) = prev {
            let d = p - q;
            if d > PI {
                offset -= 2.0 * PI;
            } else if d < -PI {
                offset += 2.0 * PI;
            }
        }
        prev = Some(p);
        out.push(p + offset);
    }
    out
}

impl TfFigures {
    /// Peak, low-frequency gain and phase figures of a sampled table TF (ascending grid).
    /// The low-frequency gain is read at the first grid point at or above
    /// [`LOW_FREQUENCY_HZ`]. `None` when the grid does not span +-1 Hz around the peak.
    pub fn from_frf(frf: &Frf) -> Option<TfFigures> {
        let f = &frf.frequency_hz;
        let h = &frf.response;
        if f.len() < 5 || h.iter().any(|z| !z.re.is_finite() || !z.im.is_finite()) {
            return None;
        }
        let mag: Vec<f64> = h.iter().map(|z| z.norm()).collect();
        let ip = (0..f.len()).max_by(|&i, &j| mag[i].total_cmp(&mag[j]))?;
        // parabolic refinement of the peak on the grid
        let (peak_hz, peak_gain) = if ip > 0 && ip + 1 < f.len() {
            let (y0, y1, y2) = (mag[ip - 1], mag[ip], mag[ip + 1]);
            let den = y0 - 2.0 * y1 + y2;
            let d = if den.abs() > 0.0 {
                0.5 * (y0 - y2) / den
            } else {
                0.0
            };
            let step = 0.5 * (f[ip + 1] - f[ip - 1]);
            (f[ip] + d * step, y1 - 0.25 * (y0 - y2) * d)
        } else {
            (f[ip], mag[ip])
        };
        let il = f.iter().position(|&x| x >= LOW_FREQUENCY_HZ)?;
        let low = mag[il];
        let phase = unwrapped_phase(h);
        let at = |x: f64| -> Option<f64> {
            let i = f.partition_point(|&g| g < x);
            if i == 0 || i >= f.len() {
                return None;
            }
            let w = (x - f[i - 1]) / (f[i] - f[i - 1]);
            Some(phase[i - 1] + w * (phase[i] - phase[i - 1]))
        };
        let drop = (at(peak_hz - 1.0)? - at(peak_hz + 1.0)?).to_degrees();
        let mut steepest = (f64::NEG_INFINITY, peak_hz);
        for i in 1..f.len() {
            let mid = 0.5 * (f[i] + f[i - 1]);
            if (mid - peak_hz).abs() <= 1.0 {
                let slope = -(phase[i] - phase[i - 1]) / (f[i] - f[i - 1]);
                if slope > steepest.0 {
                    steepest = (slope, mid);
                }
            }
        }
        Some(TfFigures {
            peak_hz,
            peak_gain,
            low_frequency_gain: low,
            peak_ratio: peak_gain / low,
            phase_drop_deg: drop,
            steepest_hz: steepest.1,
        })
    }
}

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
    // each reduced coordinate: (full-state direction, step)
    let mut dirs: Vec<([f64; NX], f64)> = Vec::new();
    let unit = |i: usize| {
        let mut d = [0.0; NX];
        d[i] = 1.0;
        d
    };
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
    let n = dirs.len();
    // project a full-state derivative onto the reduced coordinates
    let reduce = |ds: &[f64; NX]| -> DVector<f64> {
        let v: Vec<f64> = dirs
            .iter()
            .map(|(d, _)| {
                if d[ix::PA] != 0.0 && nonlinear {
                    ds[ix::PA] - ds[ix::PB]
                } else {
                    let i = d.iter().position(|&x| x != 0.0).unwrap_or(0);
                    ds[i]
                }
            })
            .collect();
        DVector::from_vec(v)
    };
    let rest = model.rest_state();
    let noise = SensorNoise::default();
    let eval = |s: &[f64; NX], inp: &Inputs| {
        let mut ds = [0.0; NX];
        model.derivatives(s, inp, &noise, 0.0, &mut ds);
        reduce(&ds)
    };
    let zero = Inputs::default();
    let mut a = DMatrix::zeros(n, n);
    for (j, (d, h)) in dirs.iter().enumerate() {
        let mut sp = rest;
        let mut sm = rest;
        for i in 0..NX {
            sp[i] += h * d[i];
            sm[i] -= h * d[i];
        }
        let col = (eval(&sp, &zero) - eval(&sm, &zero)) / (2.0 * h);
        a.set_column(j, &col);
    }
    let mut b = DMatrix::zeros(n, 3);
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
        let col = (eval(&rest, &mk(1.0)) - eval(&rest, &mk(-1.0))) / (2.0 * h);
        b.set_column(j, &col);
    }
    Ok((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pade_matches_delay_at_low_frequency() {
        let v = ValveTf::Delay {
            gain: 1.0,
            tau_s: 0.0137,
        };
        let (a, b, c, d) = v.state_space();
        for f in [1.0, 10.0, 30.0] {
            let s = jw(f);
            let n = a.nrows();
            let m = DMatrix::from_fn(n, n, |i, j| {
                (if i == j { s } else { Complex64::new(0.0, 0.0) }) - a[(i, j)]
            });
            let x = m.lu().solve(&b.map(|x| Complex64::new(x, 0.0))).unwrap();
            let h: Complex64 = (0..n).map(|i| c[i] * x[i]).sum::<Complex64>() + d;
            // Pade(4,4) error grows like (s tau)^9: 1e-7 at 1 Hz, ~2e-4 at 30 Hz
            let tol = if f <= 10.0 { 1e-5 } else { 1e-3 };
            assert!(
                (h - v.response(s)).norm() < tol,
                "f={f}: {h} vs {}",
                v.response(s)
            );
        }
    }

    #[test]
    fn phase_unwrap_is_continuous() {
        let h: Vec<Complex64> = (0..200)
            .map(|i| Complex64::from_polar(1.0, -0.1 * i as f64))
            .collect();
        let p = unwrapped_phase(&h);
        assert!((p[199] + 19.9).abs() < 1e-9);
    }
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
            damping_ratio: a.leakage_m3_s_pa / a.piston_area_m2
                * (a.bulk_modulus_pa * p.table.mass_kg / a.total_oil_volume_m3).sqrt(),
        }
    }

    /// The bulk modulus that gives `frequency_hz` for mass `mass_kg` and the geometry
    /// (`A`, `V_t`): `beta = (2 pi f)^2 M V_t / (4 A^2)` (paper 4.1.3).
    pub fn bulk_modulus_pa(frequency_hz: f64, mass_kg: f64, area_m2: f64, volume_m3: f64) -> f64 {
        (2.0 * PI * frequency_hz).powi(2) * mass_kg * volume_m3 / (4.0 * area_m2 * area_m2)
    }
}
