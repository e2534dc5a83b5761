//! The open-loop plant at rest, written analytically from the parameters (spec sections
//! 4, 5 and 7): the ideal actuator's load pressure, the table with the Bouc-Wen friction
//! linearised at `Z = 0`, each specimen mode, the foundation and an engaged free-play rod.

use super::meas;
use crate::params::Params;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use std::f64::consts::PI;

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

impl Plant {
    /// The analytic plant at rest (spec sections 4, 5 and 7).
    pub fn new(p: &Params) -> Plant {
        let act = &p.actuator;
        let m = p.table.mass_kg;
        let area = act.piston_area_m2;
        let rate = act.pressure_rate_pa_m3();
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
        let fnd = p.foundation.enabled.then_some(names.len());
        if fnd.is_some() {
            names.extend(["foundation_x", "foundation_v"]);
        }
        // free play: the contact linearised as engaged when the gap is 0; with a gap the
        // rod rests inside it and the small-signal model joins rod and table rigidly
        let rod = engaged_free_play(p).then_some(names.len());
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
