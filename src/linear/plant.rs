//! The open-loop plant at rest, written analytically from the parameters (spec sections
//! 4, 5 and 7): the ideal actuator's load pressure, the table with the Bouc-Wen friction
//! linearised at `Z = 0`, each specimen mode, the foundation and an engaged free-play rod.

use super::meas;
use crate::effects::specimen::SpecimenMode;
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
    /// The analytic plant at rest (spec sections 4, 5 and 7): the table's stroke, each
    /// specimen mode and the foundation on it, the free-play rod, then the actuator's
    /// and the table's rows and the measurements.
    pub fn new(p: &Params) -> Plant {
        let layout = StateLayout::new(p);
        let n = layout.names.len();
        let stroke = Stroke::new(p, layout.foundation, n);
        // net force on the table (spec section 5)
        let mut table_force = stroke.force.clone();
        let mut a = DMatrix::zeros(n, n);
        add_specimen_modes(&layout.modes, &mut a, &mut table_force);
        if let Some(f) = layout.foundation {
            add_foundation(p, f, &stroke.force, &mut a);
        }
        let piston = Piston::new(p, layout.rod, &stroke, &mut a, &mut table_force);
        piston.add_actuator_and_table(p, &stroke.rel_v, &mut a);
        let mut b_spool = DVector::zeros(n);
        b_spool[PL] = p.actuator.pressure_rate_pa_m3() * p.actuator.flow_gain_m3_s;
        let mut b_external = DVector::zeros(n);
        b_external[V] = 1.0 / piston.table_mass;
        Plant {
            a,
            b_spool,
            b_external,
            c: piston.measurements(p.actuator.piston_area_m2),
            names: layout.names,
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

// The states of the actuator and the table, first in every plant.
/// The load pressure `P_L`.
const PL: usize = 0;
/// The table's position `x`.
const X: usize = 1;
/// The table's velocity `v`.
const V: usize = 2;
/// The Bouc-Wen friction state `Z`.
const Z: usize = 3;

/// Which blocks the plant holds and where each one's states start in [`Plant::names`].
struct StateLayout {
    names: Vec<&'static str>,
    /// One `(x, v)` pair per present specimen mode: (mode, first state index).
    modes: Vec<(SpecimenMode, usize)>,
    /// The foundation's first state, if it is on.
    foundation: Option<usize>,
    /// The free-play rod's first state, if its contact is engaged at rest.
    rod: Option<usize>,
}

impl StateLayout {
    /// The enabled blocks in their order: actuator and table, specimen modes,
    /// foundation, free-play rod.
    fn new(p: &Params) -> StateLayout {
        let mut names = vec!["pressure_load", "table_x", "table_v", "friction_z"];
        // one (x, v) pair per present specimen mode: (mode, first state index)
        let mut modes = Vec::new();
        for (k, mode) in p.specimen.modes().into_iter().enumerate() {
            if p.specimen.enabled {
                modes.push((mode, names.len()));
                names.extend(SPECIMEN_STATE_NAMES[k]);
            }
        }
        let foundation = p.foundation.enabled.then_some(names.len());
        if foundation.is_some() {
            names.extend(["foundation_x", "foundation_v"]);
        }
        // free play: the contact linearised as engaged when the gap is 0; with a gap the
        // rod rests inside it and the small-signal model joins rod and table rigidly
        let rod = engaged_free_play(p).then_some(names.len());
        if rod.is_some() {
            names.extend(["rod_x", "rod_v"]);
        }
        StateLayout {
            names,
            modes,
            foundation,
            rod,
        }
    }
}

/// The actuator's stroke as rows over the state: the relative stroke `x - x_f`, its
/// rate, and the force between table and reaction mass `F_A - F_D - F_E`.
struct Stroke {
    rel_x: DVector<f64>,
    rel_v: DVector<f64>,
    force: DVector<f64>,
}

impl Stroke {
    /// The stroke rows for `n` states, relative to the foundation at `foundation` if on;
    /// the friction amplitude at rest is `r_s F_mu` with stick-slip.
    fn new(p: &Params, foundation: Option<usize>, n: usize) -> Stroke {
        let area = p.actuator.piston_area_m2;
        // stick-slip: the amplitude at zero velocity is r_s F_mu
        let friction = p.friction.force_n
            * if p.stick_slip.enabled {
                p.stick_slip.static_ratio
            } else {
                1.0
            };
        // the relative stroke `x - x_f` and its rate as rows over the state
        let mut rel_x = DVector::zeros(n);
        let mut rel_v = DVector::zeros(n);
        rel_x[X] = 1.0;
        rel_v[V] = 1.0;
        if let Some(f) = foundation {
            rel_x[f] = -1.0;
            rel_v[f + 1] = -1.0;
        }
        // force between table and reaction mass: F_A - F_D - F_E
        let mut force = DVector::zeros(n);
        force[PL] = area;
        force[Z] = -friction;
        force -= &rel_x * p.table.stiffness_n_m;
        Stroke {
            rel_x,
            rel_v,
            force,
        }
    }
}

/// Add each specimen mode's rows (spec section 7): a mass on a spring-damper to the
/// table, whose force the table feels back through `table_force`.
fn add_specimen_modes(
    modes: &[(SpecimenMode, usize)],
    a: &mut DMatrix<f64>,
    table_force: &mut DVector<f64>,
) {
    let n = a.nrows();
    for &(mode, s) in modes {
        let w = 2.0 * PI * mode.frequency_hz;
        let ks = mode.mass_kg * w * w;
        let cs = 2.0 * mode.damping_ratio * mode.mass_kg * w;
        // spring-damper force on the specimen: -k_s (x_s - x) - c_s (v_s - v)
        let mut on_specimen = DVector::zeros(n);
        on_specimen[s] = -ks;
        on_specimen[X] = ks;
        on_specimen[s + 1] = -cs;
        on_specimen[V] = cs;
        *table_force -= &on_specimen;
        a[(s, s + 1)] = 1.0;
        a.set_row(s + 1, &(on_specimen / mode.mass_kg).transpose());
    }
}

/// Add the foundation's rows at its first state `f` (spec section 7): the reaction
/// mass on its own spring-damper, pushed back by the stroke's force.
fn add_foundation(p: &Params, f: usize, stroke_force: &DVector<f64>, a: &mut DMatrix<f64>) {
    let w = 2.0 * PI * p.foundation.frequency_hz;
    let mf = p.foundation.mass_kg;
    let mut row = -stroke_force;
    row[f] -= mf * w * w;
    row[f + 1] -= 2.0 * p.foundation.damping_ratio * mf * w;
    a[(f, f + 1)] = 1.0;
    a.set_row(f + 1, &(row / mf).transpose());
}

/// What the LVDT and the flow follow (the piston: the rod's with engaged free play), the
/// table's acceleration as a row over the state, and the mass it moves.
struct Piston {
    lvdt_x: DVector<f64>,
    lvdt_v: DVector<f64>,
    accel: DVector<f64>,
    table_mass: f64,
}

impl Piston {
    /// The piston's rows once every block is in: the engaged free-play rod at `rod`, if
    /// any, is added to `a` and `table_force` here (spec section 7).
    fn new(
        p: &Params,
        rod: Option<usize>,
        stroke: &Stroke,
        a: &mut DMatrix<f64>,
        table_force: &mut DVector<f64>,
    ) -> Piston {
        // the LVDT and the flow follow the piston: the rod's with engaged free play
        let (mut lvdt_x, mut lvdt_v) = (stroke.rel_x.clone(), stroke.rel_v.clone());
        let mut table_mass = p.table.mass_kg;
        if let Some(r) = rod {
            let rows = RodRows {
                r,
                area: p.actuator.piston_area_m2,
            };
            table_mass = rows.add(p, a, table_force, &mut lvdt_x, &mut lvdt_v);
        }
        let accel = &*table_force / table_mass;
        Piston {
            lvdt_x,
            lvdt_v,
            accel,
            table_mass,
        }
    }

    /// The rows of the load pressure (flow continuity, spec section 4, ideal form), the
    /// table's motion and the friction state (Bouc-Wen at `Z = 0`, eq. 4.15).
    fn add_actuator_and_table(&self, p: &Params, rel_v: &DVector<f64>, a: &mut DMatrix<f64>) {
        let act = &p.actuator;
        let area = act.piston_area_m2;
        let rate = act.pressure_rate_pa_m3();
        // flow continuity (spec section 4, ideal form)
        let mut pl_row = -&self.lvdt_v * (rate * area);
        pl_row[PL] -= rate * act.leakage_m3_s_pa;
        a.set_row(PL, &pl_row.transpose());
        a[(X, V)] = 1.0;
        a.set_row(V, &self.accel.transpose());
        // Bouc-Wen at Z = 0 (eq. 4.15): Z' = v_rel / Y
        a.set_row(Z, &(rel_v / p.friction.yield_displacement_m).transpose());
    }

    /// The measurement rows `c` (see [`super::meas`]): LVDT displacement and velocity,
    /// table acceleration, and the actuator force `A P_L`.
    fn measurements(&self, area: f64) -> DMatrix<f64> {
        let mut c = DMatrix::zeros(4, self.lvdt_x.len());
        c.set_row(meas::DISPLACEMENT, &self.lvdt_x.transpose());
        c.set_row(meas::VELOCITY, &self.lvdt_v.transpose());
        c.set_row(meas::ACCELERATION, &self.accel.transpose());
        c[(meas::FORCE, PL)] = area;
        c
    }
}

/// Where the engaged free-play rod sits in the plant (spec section 7, second part): the
/// rod's first state, and the piston area its actuator force acts on.
struct RodRows {
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
        let (x, v, r) = (X, V, self.r);
        let c = p.free_play.contact();
        let mut contact = DVector::zeros(a.nrows());
        contact[r] = c.stiffness_n_m;
        contact[x] = -c.stiffness_n_m;
        contact[r + 1] = c.damping_n_s_m;
        contact[v] = -c.damping_n_s_m;
        table_force[PL] -= self.area;
        *table_force += &contact;
        let mut rod_force = -contact;
        rod_force[PL] += self.area;
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
