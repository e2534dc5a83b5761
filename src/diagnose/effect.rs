//! The catalogue effects diagnosis fits (spec section 7): names, parameters, where
//! their signature lives, how they are read from and applied to parameters, fitting bounds.

use super::effect_table::{FitKind, Row, TABLE};
use super::effect_values::{EffectBounds, EffectValues};
use super::residuals::Channel;
use crate::campaign::{Campaign, Measured, TestKind};
use crate::effects::SignatureTests;
use crate::identify::select::{excitation_roles, sine_split, slowest_first};
use crate::params::Params;
use serde::Serialize;

/// One effect the diagnosis fits (spec section 7): a catalogue entry, or the `specimen`
/// with a second or third mode; its row of [`TABLE`] says how it is fitted. Named in the
/// JSON by its catalogue entry (a specimen of several modes lists them in `modes`).
#[derive(Clone, Copy)]
pub struct Effect(&'static Row);

impl PartialEq for Effect {
    fn eq(&self, other: &Effect) -> bool {
        self.name() == other.name() && self.specimen_modes() == other.specimen_modes()
    }
}

impl Eq for Effect {}

impl std::fmt::Debug for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.specimen_modes() {
            Some(n) if n > 1 => write!(f, "{} ({n} modes)", self.name()),
            _ => write!(f, "{}", self.name()),
        }
    }
}

impl Serialize for Effect {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl Effect {
    /// The diagnosis' effect of the catalogue entry `entry` (a specimen with its one mode).
    ///
    /// # Panics
    /// When [`TABLE`] has no row for it (a unit test checks that every entry has one).
    pub fn of(entry: &crate::effects::Effect) -> Effect {
        TABLE
            .iter()
            .find(|r| r.catalogue.name == entry.name && r.specimen_modes.unwrap_or(1) == 1)
            .map(Effect)
            .unwrap_or_else(|| panic!("no diagnosis row for `{}`", entry.name))
    }

    /// The specimen with `modes` modes (1 to 3), `None` beyond.
    pub fn specimen(modes: usize) -> Option<Effect> {
        TABLE
            .iter()
            .find(|r| r.specimen_modes == Some(modes))
            .map(Effect)
    }

    /// The effects the first search fits: the whole catalogue, in its order. A specimen
    /// candidate is then fitted with one mode more while each helps ([`Effect::next_mode`]).
    pub fn search_order() -> Vec<Effect> {
        crate::effects::CATALOGUE.iter().map(Effect::of).collect()
    }

    /// Whether this is the catalogue entry `entry`'s effect (a specimen of any modes).
    pub fn is(self, entry: &crate::effects::Effect) -> bool {
        self.name() == entry.name
    }

    /// The catalogue entry of this effect ([`crate::effects::CATALOGUE`], the one place
    /// its parameters, FMU variables, fitting ranges and signature tests are declared).
    pub fn catalogue(self) -> &'static crate::effects::Effect {
        self.0.catalogue
    }

    /// How the diagnosis fits it ([`TABLE`]).
    pub(super) fn row(self) -> &'static Row {
        self.0
    }

    /// The specimen with one mode more (a building model's modes show one by one, each
    /// behind the one before), `None` for the other effects and at three modes.
    pub(super) fn next_mode(self) -> Option<Effect> {
        Effect::specimen(self.specimen_modes()? + 1)
    }

    /// The key among [`Effect::parameters`] of the resonance frequency whose starts lie
    /// in different valleys of the fit ([`Row::valley_frequency`]), `None` for the
    /// effects without one.
    pub(super) fn valley_frequency(self) -> Option<&'static str> {
        self.0.valley_frequency
    }

    /// Its place in the search's fitting order, longest fits first: the predictive-score
    /// polishes (free play's, stick-slip's), then the resonances with starts in several
    /// valleys, then the rest. Started in catalogue order, the free play's fit (87 s of
    /// a 117-s search, seed 459) began 30 s in and ran alone on one core for its last
    /// 66 s; stick-slip's (42 s, seed 454) began 19 s in.
    pub(super) fn fitting_rank(self) -> u8 {
        match (self.0.fit, self.0.valley_frequency) {
            (FitKind::FreePlay | FitKind::StickSlip, _) => 0,
            (FitKind::OutputError, Some(_)) => 1,
            (FitKind::OutputError, None) => 2,
        }
    }

    /// The key among [`Effect::parameters`] of the specimen's newest mode's mass (the mode
    /// its fit adds), `None` for the other effects.
    pub(super) fn newest_mode_mass(self) -> Option<&'static str> {
        match self.specimen_modes()? {
            1 => Some("mass_kg"),
            2 => Some("mode2.mass_kg"),
            _ => Some("mode3.mass_kg"),
        }
    }

    /// The specimen's modes (1 to 3), `None` for the other effects.
    pub fn specimen_modes(self) -> Option<usize> {
        self.0.specimen_modes
    }

    pub fn name(self) -> &'static str {
        self.catalogue().name
    }

    /// Parameter names (spec section 7), in declaration order.
    pub fn parameters(self) -> Vec<&'static str> {
        self.catalogue().parameters.iter().map(|q| q.key).collect()
    }

    /// The values of its parameters at which it vanishes ([`crate::effects::Effect::no_effect`]).
    pub(super) fn no_effect(self) -> &'static [(&'static str, f64)] {
        self.catalogue().no_effect
    }

    /// Whether `c` records what its signature needs ([`crate::effects::Effect::signature_channels`]):
    /// `Err` names the alternatives when it does not (the effect is not testable).
    pub(super) fn testable(self, c: &Campaign) -> Result<(), String> {
        let recorded = |m: Measured| c.records.iter().any(|r| r.measured(m).is_some());
        let alternatives = self.catalogue().signature_channels;
        if alternatives
            .iter()
            .any(|set| set.iter().all(|&m| recorded(m)))
        {
            return Ok(());
        }
        // the channels as the diagnosis names them (JSON, reports)
        let named = |m: &Measured| {
            Channel::ALL
                .into_iter()
                .find(|ch| ch.recorded() == *m)
                .map_or(m.name(), Channel::name)
        };
        let needs: Vec<String> = alternatives
            .iter()
            .map(|set| set.iter().map(named).collect::<Vec<_>>().join(" and "))
            .collect();
        Err(format!(
            "{} not testable: its signature needs the {} channel, and no test recorded it",
            self.name(),
            needs.join(" or the ")
        ))
    }

    /// The tests of `c` where its signature lives
    /// ([`crate::effects::Effect::signature_tests`]), in campaign order; the friction-
    /// and inertia-dominated sines are told apart on `table`.
    pub(super) fn signature_tests(self, c: &Campaign, table: &Params) -> Vec<usize> {
        tests_of(c, table, &self.catalogue().signature_tests)
    }

    /// The catalogue effects switched on in `p`, a specimen as the variant of its modes
    /// (a mode exists when its mass is positive, spec section 7).
    pub(super) fn present_in(p: &Params) -> Vec<Effect> {
        let modes = |n: usize| Effect::specimen(n).expect("the specimen's modes");
        let has = |key: &str| EffectValues::read(modes(3), p).get(key) > 0.0;
        Effect::search_order()
            .into_iter()
            .filter(|e| e.catalogue().is_enabled(p))
            .map(|e| match e.specimen_modes() {
                Some(_) if has("mode3.mass_kg") => modes(3),
                Some(_) if has("mode2.mass_kg") => modes(2),
                _ => e,
            })
            .collect()
    }

    /// Whether its signature has no reproducible phase (stick-slip's chatter grows out of
    /// the sensor noise, the free play's bounces inside the gap are chaotic): it is fitted
    /// on the predictive score and held in output-error refinements, whose sample-wise
    /// residual is rough at the scale of a percent in its parameters.
    pub(super) fn fitted_on_score(self) -> bool {
        self.0.fit != FitKind::OutputError
    }

    /// The fitting bounds for `table`, by key.
    pub(super) fn bounds(self, table: &Params) -> EffectBounds {
        EffectBounds::of(self, table)
    }
}

/// The tests of `c` that `wanted` describes ([`crate::effects::SignatureTests`]), in
/// campaign order; the friction- and inertia-dominated sines are told apart on `table`.
pub(super) fn tests_of(c: &Campaign, table: &Params, wanted: &SignatureTests) -> Vec<usize> {
    let roles = excitation_roles(c);
    let (slow, fast) = sine_split(c, table.table.mass_kg, table.friction.force_n);
    let triangles: Vec<usize> = (0..c.info.tests.len())
        .filter(|&i| c.info.tests[i].kind == TestKind::Triangle)
        .collect();
    let mut picked: Vec<usize> = wanted.random.iter().filter_map(|&r| roles.of(r)).collect();
    picked.extend(slowest_first(c, &slow).into_iter().take(wanted.slow_sines));
    picked.extend(
        slowest_first(c, &triangles)
            .into_iter()
            .take(wanted.slow_triangles),
    );
    picked.extend(
        slowest_first(c, &fast)
            .into_iter()
            .rev()
            .take(wanted.fast_sines),
    );
    picked.sort_unstable();
    picked.dedup();
    picked
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::{specimen, valve_deadband};

    /// The effects a model holds are read off its parameters, a specimen as its modes: the
    /// polish refits each of them (an accepted cause refitted with the next).
    #[test]
    fn the_effects_present_are_read_off_the_parameters() {
        let mut p = Params::default();
        assert!(Effect::present_in(&p).is_empty());
        p.apply_effect_spec("valve_deadband:deadband=0.01").unwrap();
        p.apply_effect_spec("specimen:mass_kg=1e4,frequency_hz=4")
            .unwrap();
        assert_eq!(
            Effect::present_in(&p),
            [
                Effect::of(&specimen::EFFECT),
                Effect::of(&valve_deadband::EFFECT)
            ]
        );
        p.apply_effect_spec("specimen:mode2.mass_kg=2e3,mode2.frequency_hz=9")
            .unwrap();
        let two_modes = Effect::specimen(2).unwrap();
        assert_eq!(
            Effect::present_in(&p),
            [two_modes, Effect::of(&valve_deadband::EFFECT)]
        );
        let values = EffectValues::read(two_modes, &p);
        assert_eq!(values.get("mode2.frequency_hz"), 9.0);
        assert_eq!(values.finite_map().len(), 6);
    }

    /// Each diagnosis effect is the catalogue entry of its name, and the search takes the
    /// catalogue's order.
    #[test]
    fn every_effect_is_its_catalogue_entry() {
        for e in TABLE.iter().map(Effect) {
            // the variant's own name (its JSON form) is its catalogue entry's
            let variant = serde_json::to_string(&e).unwrap();
            assert_eq!(variant, format!("\"{}\"", e.catalogue().name));
            let entry = crate::effects::by_name(e.name()).unwrap();
            let mut p = Params::trees_lab();
            let mut values = EffectValues::read(e, &p);
            for (key, x) in EffectValues::read(e, &p).iter() {
                values.set(key, x * 1.1 + 0.001);
            }
            values.apply(&mut p);
            assert!(entry.is_enabled(&p));
            assert_eq!(EffectValues::read(e, &p), values);
        }
        let names: Vec<&str> = Effect::search_order().iter().map(|e| e.name()).collect();
        let catalogue: Vec<&str> = crate::effects::CATALOGUE.iter().map(|e| e.name).collect();
        assert_eq!(names, catalogue);
    }

    /// The signature tests are chosen by what they excite: on the paper's program under a
    /// laboratory's names, each effect gets the paper's tests.
    #[test]
    fn signature_tests_are_the_papers_under_any_name() {
        let opts = crate::campaign::synth::SynthOptions {
            random_duration_s: 12.0,
            ..Default::default()
        };
        let mut c = crate::campaign::synth::synthesise(&Params::trees_lab(), &opts, None);
        for (k, t) in c.info.tests.iter_mut().enumerate() {
            t.name = format!("run_{:02}_{}", 17 - k, t.name);
        }
        let paper = |e: Effect| -> &[&str] {
            match e.name() {
                "specimen" => &["R2", "R3"],
                "foundation" => &["R1", "R3", "S9"],
                "stick_slip" => &["S1", "S2", "S4", "S5", "S7", "S8", "T1", "T3"],
                "flow_saturation" | "flow_asymmetry" => &["R2", "S6", "S9"],
                "valve_deadband" => &["R2", "S1", "T1", "T3"],
                "friction_asymmetry" => &["S1", "S4", "T1", "T3"],
                "free_play" => &["R1", "S9"],
                other => panic!("no paper tests for {other}"),
            }
        };
        let check = |c: &Campaign| {
            for e in Effect::search_order() {
                let names: Vec<&str> = e
                    .signature_tests(c, &Params::trees_lab())
                    .into_iter()
                    .map(|i| c.info.tests[i].name.rsplit('_').next().unwrap())
                    .collect();
                assert_eq!(names, paper(e), "{}", e.name());
            }
        };
        check(&c);
        // recorded by the displacement alone: the same tests (their excitation is the same)
        for r in &mut c.records {
            r.acceleration_m_s2 = None;
            r.force_n = None;
            r.spool_position = None;
            r.valve_command = None;
        }
        check(&c);
    }
}
