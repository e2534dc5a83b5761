//! Physically informed starts of the candidates' fits: the apparent mass of the random
//! tests (specimen, foundation), the velocity plateau (flow saturation), small grids.

use super::effect::Effect;
use super::effect_table::StartsFrom;
use super::effect_values::EffectValues;
use super::specimen_modes::apart;
use crate::campaign::{Campaign, TestKind};
use crate::identify;
use crate::identify::frf::{FrfEstimate, Welch, WelchOptions};
use crate::identify::select::random_roles;
use crate::params::Params;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The rod's start as a share of the moving mass: the catalogue's 1.5 t rod and piston of
/// the 41 t TREES Lab table (`free_play`'s default), scaled to the table.
pub(super) const ROD_MASS_FRACTION: f64 = 0.036;

/// Start grids of the candidates' fits, in the table's terms where the effect scales with
/// it. They only seed the fits (the caller screens every start and fits the best two), so
/// they span each effect's plausible range coarsely rather than finely.
pub(super) mod grid {
    /// Apparent-mass resolution of the specimen's and foundation's FRF starts (Hz): four
    /// lines per hertz separate modes a few percent apart.
    pub const APPARENT_MASS_RESOLUTION_HZ: f64 = 0.25;
    /// Welch segments the apparent mass averages at least (its variance).
    pub const APPARENT_MASS_MIN_SEGMENTS: usize = 8;
    /// The band of the apparent mass (Hz): where the random tests excite the table.
    pub const APPARENT_MASS_BAND_HZ: [f64; 2] = [1.0, 40.0];
    /// Specimen masses (table masses) at the apparent mass's peak.
    pub const SPECIMEN_MASS_RATIOS: [f64; 2] = [0.1, 0.3];
    /// Without the apparent mass (no force or acceleration channel in a random test), a
    /// blind grid over the building-model range (Hz) at a light and a heavy specimen
    /// (table masses): a single start at 5 Hz slid to a 200-kg mode when the specimen was
    /// 30 t at 4 Hz.
    pub const SPECIMEN_BLIND_FREQUENCIES_HZ: [f64; 5] = [1.5, 3.0, 5.0, 8.0, 13.0];
    pub const SPECIMEN_BLIND_MASS_RATIOS: [f64; 2] = [0.15, 0.6];
    /// A specimen's or foundation's starting damping ratios: typical of steel or RC
    /// models (3 %) and of a foundation block on soil (5 %).
    pub const SPECIMEN_DAMPING: f64 = 0.03;
    pub const FOUNDATION_DAMPING: f64 = 0.05;
    /// Foundation masses (table masses) at the data's frequency, and the blind grid of
    /// frequencies (Hz) and masses over the plausible band.
    pub const FOUNDATION_INFORMED_MASS_RATIOS: [f64; 3] = [3.0, 10.0, 40.0];
    pub const FOUNDATION_FREQUENCIES_HZ: [f64; 4] = [8.0, 15.0, 25.0, 40.0];
    pub const FOUNDATION_MASS_RATIOS: [f64; 2] = [3.0, 20.0];
    /// Stick-slip static ratios and Stribeck velocities (m/s).
    pub const STICK_SLIP_RATIOS: [f64; 3] = [1.5, 2.5, 3.5];
    pub const STRIBECK_VELOCITIES_M_S: [f64; 2] = [0.002, 0.006];
    /// Samples over which the sines' speed is differenced (the plateau, not its noise).
    pub const PLATEAU_LAG_SAMPLES: usize = 8;
    /// The least flow-limit start (m^3/s): a table at rest has no plateau.
    pub const MIN_FLOW_START_M3_S: f64 = 1e-3;
    /// Deadbands (fractions of the rated spool) and asymmetry ratios either side of 1.
    pub const DEADBANDS: [f64; 2] = [0.01, 0.03];
    pub const ASYMMETRY_RATIOS: [f64; 2] = [0.7, 1.4];
}

/// Apparent mass `F/a` of the mass test (R2 in the paper; else the oil-column test:
/// [`crate::identify::select`]), the reference acceleration as instrument, on 1-40 Hz.
pub(super) fn apparent_mass(c: &Campaign) -> Option<(Vec<f64>, Vec<Complex64>)> {
    let i = apparent_mass_test(c)?;
    let (r, fs) = (&c.records[i], c.sample_rate_of(i));
    let w = Welch::new(
        fs,
        WelchOptions::for_resolution(fs, grid::APPARENT_MASS_RESOLUTION_HZ)
            .fit_to(r.len(), grid::APPARENT_MASS_MIN_SEGMENTS),
    )
    .ok()?;
    let e = w
        .frf_instrumental(
            &r.ref_acceleration_m_s2,
            r.acceleration_m_s2.as_deref()?,
            r.force_n.as_deref()?,
        )
        .ok()?;
    Some(in_band(&e))
}

/// [`apparent_mass`] with `base`'s friction and table stiffness taken out of the force
/// along the measured path, as identify's mass fit reads it
/// ([`identify::apparent_mass_less_friction`], at identify's resolution, the same 0.25 Hz):
/// what a table carrying modes is fitted to.
pub(super) fn apparent_mass_less_friction(
    c: &Campaign,
    base: &Params,
) -> Option<(Vec<f64>, Vec<Complex64>)> {
    let i = apparent_mass_test(c)?;
    let e = identify::apparent_mass_less_friction(
        &c.info.tests[i].name,
        &c.records[i],
        c.sample_rate_of(i),
        &base.friction,
        base.table.stiffness_n_m,
    )
    .ok()?;
    Some(in_band(&e))
}

/// The test the apparent mass is read from: the mass test, else the oil-column test.
fn apparent_mass_test(c: &Campaign) -> Option<usize> {
    let roles = random_roles(c);
    roles.mass.or(roles.oil_column)
}

/// The bins of `e` in [`grid::APPARENT_MASS_BAND_HZ`]: frequencies and `F/a`.
fn in_band(e: &FrfEstimate) -> (Vec<f64>, Vec<Complex64>) {
    let [lo, hi] = grid::APPARENT_MASS_BAND_HZ;
    let idx = e.band(lo, hi);
    (
        idx.iter().map(|&i| e.frequency_hz[i]).collect(),
        idx.iter().map(|&i| e.h1[i]).collect(),
    )
}

/// Starting points of a candidate's effect parameters (physically informed): its row's
/// ([`super::effect_table::Row::starts`]).
pub(super) fn starts(
    effect: Effect,
    c: &Campaign,
    base: &Params,
    informed: Option<&EffectValues>,
) -> Vec<EffectValues> {
    (effect.row().starts)(&StartsFrom {
        effect,
        c,
        base,
        informed,
    })
}

/// The values of an effect of one parameter (a deadband, a ratio, a flow limit).
pub(super) fn one_value(effect: Effect, value: f64) -> EffectValues {
    let keys = effect.parameters();
    EffectValues::new(effect, &[(keys[0], value)])
}

/// A deadband's grid ([`grid::DEADBANDS`]).
pub(super) fn deadband_grid(effect: Effect) -> Vec<EffectValues> {
    grid::DEADBANDS
        .iter()
        .map(|&d| one_value(effect, d))
        .collect()
}

/// An asymmetry's grid either side of symmetry ([`grid::ASYMMETRY_RATIOS`]).
pub(super) fn asymmetry_grid(effect: Effect) -> Vec<EffectValues> {
    grid::ASYMMETRY_RATIOS
        .iter()
        .map(|&r| one_value(effect, r))
        .collect()
}

/// A resonance's values (the specimen's first mode, the foundation).
pub(super) fn resonance(
    effect: Effect,
    mass_kg: f64,
    frequency_hz: f64,
    damping_ratio: f64,
) -> EffectValues {
    EffectValues::new(
        effect,
        &[
            ("mass_kg", mass_kg),
            ("frequency_hz", frequency_hz),
            ("damping_ratio", damping_ratio),
        ],
    )
}

/// Stick-slip's grid: every static ratio at every Stribeck velocity.
pub(super) fn stick_slip_grid() -> Vec<EffectValues> {
    let mut g = Vec::new();
    for r in grid::STICK_SLIP_RATIOS {
        for v in grid::STRIBECK_VELOCITIES_M_S {
            g.push(EffectValues::new(
                Effect::of(&crate::effects::stick_slip::EFFECT),
                &[("static_ratio", r), ("stribeck_velocity_m_s", v)],
            ));
        }
    }
    g
}

/// A foundation's starts on a table of `table_mass_kg`: the FRF fit's (`informed`,
/// [`foundation_start`]) and a spread over the plausible band, screened by the caller.
/// The FRF fit places the mode to a few percent; its mass and damping trade off on a
/// smeared peak, so the mass is spread.
pub(super) fn foundation_starts(
    table_mass_kg: f64,
    informed: Option<&EffectValues>,
) -> Vec<EffectValues> {
    let m = table_mass_kg;
    let e = Effect::of(&crate::effects::foundation::EFFECT);
    let mut g: Vec<EffectValues> = Vec::new();
    if let Some(f) = informed {
        for r in grid::FOUNDATION_INFORMED_MASS_RATIOS {
            g.push(resonance(
                e,
                r * m,
                f.get("frequency_hz"),
                grid::FOUNDATION_DAMPING,
            ));
        }
    }
    g.extend(resonance_grid(
        e,
        m,
        &grid::FOUNDATION_FREQUENCIES_HZ,
        &grid::FOUNDATION_MASS_RATIOS,
        grid::FOUNDATION_DAMPING,
    ));
    g
}

/// The flow limit's start, m^3/s: the velocity plateau of the fastest sines times the
/// piston area (at least [`grid::MIN_FLOW_START_M3_S`]).
pub(super) fn flow_limit_start(c: &Campaign, base: &Params) -> f64 {
    let mut vmax: f64 = 0.0;
    for (spec, r) in c.info.tests.iter().zip(&c.records) {
        if let (TestKind::Sine, Some(x)) = (spec.kind, r.displacement_m.as_deref()) {
            let fs = c.sample_rate_for(spec);
            let lag = grid::PLATEAU_LAG_SAMPLES;
            for k in lag..x.len() {
                vmax = vmax.max(((x[k] - x[k - lag]) * fs / lag as f64).abs());
            }
        }
    }
    let q = vmax * base.actuator.piston_area_m2;
    q.max(grid::MIN_FLOW_START_M3_S)
}

/// The specimen's blind grid ([`grid::SPECIMEN_BLIND_FREQUENCIES_HZ`]) on a table of
/// `table_mass_kg`.
pub(super) fn specimen_blind_grid(table_mass_kg: f64) -> Vec<EffectValues> {
    resonance_grid(
        Effect::of(&crate::effects::specimen::EFFECT),
        table_mass_kg,
        &grid::SPECIMEN_BLIND_FREQUENCIES_HZ,
        &grid::SPECIMEN_BLIND_MASS_RATIOS,
        grid::SPECIMEN_DAMPING,
    )
}

/// A blind grid of a resonance's starts (`effect`'s mass, frequency and damping ratio):
/// every frequency at every mass (table masses of `table_mass_kg`), frequency by
/// frequency.
fn resonance_grid(
    effect: Effect,
    table_mass_kg: f64,
    frequencies_hz: &[f64],
    mass_ratios: &[f64],
    damping_ratio: f64,
) -> Vec<EffectValues> {
    frequencies_hz
        .iter()
        .flat_map(|&f| {
            mass_ratios
                .iter()
                .map(move |r| resonance(effect, r * table_mass_kg, f, damping_ratio))
        })
        .collect()
}

/// The `keep` best of a resonance's screened starts (`scored`, best first), plus the best
/// start at each further frequency (`frequency_hz`), [`apart`] from those kept: starts at
/// different frequencies lead to different valleys, and one evaluation ranks a start by
/// how well its guessed mass and damping fit, not by its valley (seed 911: two starts of a
/// 4-t mode at 21 Hz screened better than the 8-t mode at 9.5 Hz that dominated the
/// residual, so the two-mode fit took 21 Hz and gained 1.07).
pub(super) fn keep_each_frequency<T>(
    scored: Vec<(f64, T)>,
    keep: usize,
    frequency_hz: impl Fn(&T) -> f64,
) -> Vec<T> {
    let mut kept_hz: Vec<f64> = Vec::new();
    let mut kept = Vec::new();
    for (k, (cost, start)) in scored.into_iter().enumerate() {
        let f = frequency_hz(&start);
        // a start whose screening run failed (infinite cost) is kept only among the best
        if k < keep || (cost.is_finite() && apart(f, &kept_hz)) {
            kept_hz.push(f);
            kept.push(start);
        }
    }
    kept
}

/// The start of `effect` read off the data (its row's
/// [`super::effect_table::Row::informed`]: the foundation's and the free play's from the
/// LVDT/accelerometer discrepancy), fitted by [`super::candidates::fit_candidate`]
/// whatever the screening says.
pub(super) fn informed_start(effect: Effect, c: &Campaign, base: &Params) -> Option<EffectValues> {
    let read = effect.row().informed?;
    read(&StartsFrom {
        effect,
        c,
        base,
        informed: None,
    })
}

/// Foundation starts from R3 (the broadest band; R2, R1 otherwise): the LVDT reads the
/// table relative to the reaction mass, the accelerometer the table alone, so with the
/// table's inertia as the force on the reaction mass (`F = -w^2 M x`) it moves by
/// `r = x_f / x = w^2 (M/M_f) / (w_f^2 - w^2 + 2 i zeta w_f w)` of the table, and
/// `D = a / (-w^2 x_lvdt) - 1 = r / (1 - r)`. `D` peaks where `r = 1`, at
/// `w_f / sqrt(1 + M/M_f)`; below the peak `D ~ (w/w_f)^2 M/M_f` gives the mass, and the
/// half-power width the damping. Returns `(M_f, f_f, zeta)` from the peak (the peak is
/// read where coherence is high, at 0.25 Hz resolution: a lightly damped mode is narrower
/// than the 0.5 Hz the other spectra use), or None when `D` has no clear peak.
pub(super) fn foundation_start(c: &Campaign, table_mass_kg: f64) -> Option<EffectValues> {
    let d = Discrepancy::read(c)?;
    let k = d.clear_peak()?;
    let f_peak = d.frequency_hz[k];
    let zeta = d.half_power_damping(k);
    let ratio = d.mass_ratio(k);
    let f_f = f_peak * (1.0 + ratio).sqrt();
    Some(resonance(
        Effect::of(&crate::effects::foundation::EFFECT),
        table_mass_kg / ratio,
        f_f,
        zeta,
    ))
}

/// Thresholds of [`foundation_start`]'s reading of the discrepancy `D`.
mod discrepancy {
    /// Line spacing of its spectra, Hz: a lightly damped foundation's peak is narrower
    /// than the 0.5 Hz the other spectra use.
    pub const RESOLUTION_HZ: f64 = 0.25;
    /// Welch segments it averages at least.
    pub const MIN_SEGMENTS: usize = 4;
    /// Where it is read, Hz: the foundation frequencies a start can take.
    pub const BAND_HZ: [f64; 2] = [3.0, 60.0];
    /// LVDT-accelerometer coherence a line needs to count: below it `D` is the sensors'
    /// noise, not the reaction mass.
    pub const MIN_COHERENCE: f64 = 0.8;
    /// Coherent lines it needs at all.
    pub const MIN_LINES: usize = 8;
    /// A clear peak stands this many times above the median level of the coherent lines.
    pub const CLEAR_PEAK_RATIO: f64 = 5.0;
    /// Lines within this share of the peak frequency count towards its half-power width
    /// (the peak's own lobe, not another one).
    pub const HALF_POWER_SPAN: f64 = 0.2;
    /// The damping ratio read off the half-power width is kept within these (a width of
    /// one line bounds it from below at a few tens of hertz; a width of 60 % is no peak).
    pub const DAMPING_RANGE: [f64; 2] = [0.005, 0.3];
    /// The mass ratio is read at the highest line below this share of the peak frequency
    /// (an octave below, where `D ~ (w/w_f)^2 M/M_f` holds).
    pub const BELOW_PEAK: f64 = 0.5;
    /// The mass ratio `M/M_f` read there is kept within these (a foundation of 0.5 to
    /// 1000 table masses).
    pub const MASS_RATIO_RANGE: [f64; 2] = [1e-3, 2.0];
    /// The mass ratio without a coherent line an octave below the peak (a foundation of
    /// 20 table masses).
    pub const MASS_RATIO_UNREAD: f64 = 0.05;
}

/// The discrepancy `|D| = |a / (-w^2 x_lvdt) - 1|` of [`foundation_start`] at the
/// coherent lines of the broadest random test.
struct Discrepancy {
    /// The coherent lines, Hz.
    frequency_hz: Vec<f64>,
    /// `|D|` at each.
    level: Vec<f64>,
    /// The spectra's line spacing, Hz.
    resolution_hz: f64,
}

impl Discrepancy {
    /// From the broadest excitation first: the oil-column test (R3), the mass test, the
    /// valve test ([`crate::identify::select`]); None without LVDT and accelerometer or
    /// with fewer than [`discrepancy::MIN_LINES`] coherent lines.
    fn read(c: &Campaign) -> Option<Discrepancy> {
        let roles = random_roles(c);
        let i = roles.oil_column.or(roles.mass).or(roles.valve)?;
        let (r, fs) = (&c.records[i], c.sample_rate_of(i));
        let w = Welch::new(
            fs,
            WelchOptions::for_resolution(fs, discrepancy::RESOLUTION_HZ)
                .fit_to(r.len(), discrepancy::MIN_SEGMENTS),
        )
        .ok()?;
        let e = w
            .frf(
                r.displacement_m.as_deref()?,
                r.acceleration_m_s2.as_deref()?,
            )
            .ok()?;
        let [lo, hi] = discrepancy::BAND_HZ;
        let idx: Vec<usize> = e
            .band(lo, hi)
            .into_iter()
            .filter(|&i| e.coherence[i] > discrepancy::MIN_COHERENCE)
            .collect();
        if idx.len() < discrepancy::MIN_LINES {
            return None;
        }
        let level = |i: usize| {
            let w = 2.0 * PI * e.frequency_hz[i];
            (e.h1[i] / (-w * w) - 1.0).norm()
        };
        Some(Discrepancy {
            frequency_hz: idx.iter().map(|&i| e.frequency_hz[i]).collect(),
            level: idx.iter().map(|&i| level(i)).collect(),
            resolution_hz: e.frequency_hz[1] - e.frequency_hz[0],
        })
    }

    /// The line of the highest level, if it stands clear of the median level
    /// ([`discrepancy::CLEAR_PEAK_RATIO`]).
    fn clear_peak(&self) -> Option<usize> {
        let n = self.level.len();
        let k = (0..n).max_by(|&a, &b| self.level[a].total_cmp(&self.level[b]))?;
        let mut levels = self.level.clone();
        levels.sort_by(f64::total_cmp);
        if self.level[k] < discrepancy::CLEAR_PEAK_RATIO * levels[n / 2] {
            return None;
        }
        Some(k)
    }

    /// The damping ratio from the half-power width of the peak at line `k`: the
    /// neighbouring lines above 1/sqrt(2) of the peak (at least one line: the resolution
    /// bounds the damping from below).
    fn half_power_damping(&self, k: usize) -> f64 {
        let (f_peak, peak) = (self.frequency_hz[k], self.level[k]);
        let above = (0..self.level.len())
            .filter(|&j| {
                (self.frequency_hz[j] - f_peak).abs() < discrepancy::HALF_POWER_SPAN * f_peak
                    && self.level[j] > peak / 2f64.sqrt()
            })
            .count()
            .max(1);
        let [lo, hi] = discrepancy::DAMPING_RANGE;
        (above as f64 * self.resolution_hz / (2.0 * f_peak)).clamp(lo, hi)
    }

    /// The mass ratio `M/M_f` from the level an octave below the peak at line `k`.
    fn mass_ratio(&self, k: usize) -> f64 {
        let f_peak = self.frequency_hz[k];
        let f = &self.frequency_hz;
        let below = (0..f.len())
            .filter(|&j| f[j] < discrepancy::BELOW_PEAK * f_peak)
            .max_by(|&a, &b| f[a].total_cmp(&f[b]));
        let [lo, hi] = discrepancy::MASS_RATIO_RANGE;
        match below {
            Some(j) => (self.level[j] * (f_peak / f[j]).powi(2)).clamp(lo, hi),
            None => discrepancy::MASS_RATIO_UNREAD,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The best starts are kept, then the best of each further frequency: 21 and 21.25 Hz
    /// are one valley, 9.5 Hz another.
    #[test]
    fn a_start_is_kept_at_each_frequency_of_the_new_mode() {
        let scored = vec![
            (1.0, 21.0),
            (1.1, 21.0),
            (1.2, 9.5),
            (1.5, 21.25),
            (2.0, 9.6),
            (3.0, 40.0),
            (f64::INFINITY, 5.0),
        ];
        let kept = keep_each_frequency(scored.clone(), 2, |f| *f);
        assert_eq!(kept, [21.0, 21.0, 9.5, 40.0]);
        assert_eq!(keep_each_frequency(scored, 1, |f| *f), [21.0, 9.5, 40.0]);
    }

    /// The frequency whose starts are told apart is the foundation's and the newest mode's.
    #[test]
    fn the_valley_frequency_is_the_resonance_a_fit_adds() {
        let key = |e: Effect| e.valley_frequency();
        assert_eq!(
            key(Effect::of(&crate::effects::foundation::EFFECT)),
            Some("frequency_hz")
        );
        assert_eq!(
            key(Effect::specimen(2).unwrap()),
            Some("mode2.frequency_hz")
        );
        assert_eq!(
            key(Effect::specimen(3).unwrap()),
            Some("mode3.frequency_hz")
        );
        assert_eq!(
            key(Effect::of(&crate::effects::specimen::EFFECT)),
            Some("frequency_hz")
        );
        assert_eq!(
            key(Effect::of(&crate::effects::valve_deadband::EFFECT)),
            None
        );
    }
}
