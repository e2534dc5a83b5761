//! The catalogue effects diagnosis fits (spec section 7): names, parameters, where
//! their signature lives, how they are read from and applied to parameters, fitting bounds.

use super::residuals::Channel;
use crate::campaign::{Campaign, Measured, TestKind};
use crate::effects::SignatureTests;
use crate::identify::select::{excitation_roles, sine_split, slowest_first};
use crate::params::Params;
use serde::Serialize;

/// Catalogue effects (spec section 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    Specimen,
    Foundation,
    StickSlip,
    FlowSaturation,
    ValveDeadband,
    FrictionAsymmetry,
    FlowAsymmetry,
    FreePlay,
    /// The specimen with a second mode, fitted on a one-mode specimen candidate; named
    /// `specimen` in the JSON, which lists its modes in `modes`.
    #[serde(rename = "specimen")]
    SpecimenTwoModes,
    /// With a third mode, fitted on a two-mode one.
    #[serde(rename = "specimen")]
    SpecimenThreeModes,
}

/// The effects the first search fits: the whole catalogue, in its order. A specimen
/// candidate is then fitted with one mode more while each helps ([`Effect::next_mode`]).
pub const EFFECTS: [Effect; 8] = [
    Effect::Specimen,
    Effect::Foundation,
    Effect::StickSlip,
    Effect::FlowSaturation,
    Effect::ValveDeadband,
    Effect::FrictionAsymmetry,
    Effect::FlowAsymmetry,
    Effect::FreePlay,
];

impl Effect {
    /// The catalogue entry of this effect ([`crate::effects::CATALOGUE`], the one place
    /// its parameters, FMU variables, fitting ranges and signature tests are declared).
    pub fn catalogue(self) -> &'static crate::effects::Effect {
        use crate::effects::specimen::{THREE_MODES, TWO_MODES};
        match self {
            Effect::SpecimenTwoModes => &TWO_MODES,
            Effect::SpecimenThreeModes => &THREE_MODES,
            // the catalogue's effects come first, in its order
            _ => &crate::effects::CATALOGUE[self as usize],
        }
    }

    /// The specimen with one mode more (a building model's modes show one by one, each
    /// behind the one before), `None` for the other effects and at three modes.
    pub(super) fn next_mode(self) -> Option<Effect> {
        match self {
            Effect::Specimen => Some(Effect::SpecimenTwoModes),
            Effect::SpecimenTwoModes => Some(Effect::SpecimenThreeModes),
            _ => None,
        }
    }

    /// The index among [`Effect::parameters`] of the resonance frequency whose starts lie
    /// in different valleys of the fit ([`super::starts::keep_each_frequency`]): the
    /// foundation's, and a specimen's newest mode's (the first mode's starts lie at one
    /// frequency when read off the apparent mass, on a blind grid without it). `None` for
    /// the other effects.
    pub(super) fn valley_frequency(self) -> Option<usize> {
        let key = match self {
            Effect::Foundation | Effect::Specimen => "frequency_hz",
            Effect::SpecimenTwoModes => "mode2.frequency_hz",
            Effect::SpecimenThreeModes => "mode3.frequency_hz",
            _ => return None,
        };
        self.parameters().iter().position(|k| *k == key)
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

    /// The value of its parameter `key` in `theta` (its parameters in the order of
    /// [`Effect::parameters`]), `None` when it has no such parameter.
    pub(super) fn value_of(self, theta: &[f64], key: &str) -> Option<f64> {
        self.parameters()
            .iter()
            .position(|k| *k == key)
            .map(|k| theta[k])
    }

    /// The specimen's modes (1 to 3), `None` for the other effects.
    pub fn specimen_modes(self) -> Option<usize> {
        match self {
            Effect::Specimen => Some(1),
            Effect::SpecimenTwoModes => Some(2),
            Effect::SpecimenThreeModes => Some(3),
            _ => None,
        }
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
        let has = |key: &str| {
            let e = Effect::SpecimenThreeModes;
            let k = e.parameters().iter().position(|n| *n == key);
            k.is_some_and(|k| e.read(p)[k] > 0.0)
        };
        EFFECTS
            .into_iter()
            .filter(|e| e.catalogue().is_enabled(p))
            .map(|e| match e {
                Effect::Specimen if has("mode3.mass_kg") => Effect::SpecimenThreeModes,
                Effect::Specimen if has("mode2.mass_kg") => Effect::SpecimenTwoModes,
                e => e,
            })
            .collect()
    }

    /// Whether its signature has no reproducible phase (stick-slip's chatter grows out of
    /// the sensor noise, the free play's bounces inside the gap are chaotic): it is fitted
    /// on the predictive score and held in output-error refinements, whose sample-wise
    /// residual is rough at the scale of a percent in its parameters.
    pub(super) fn fitted_on_score(self) -> bool {
        matches!(self, Effect::StickSlip | Effect::FreePlay)
    }

    /// The effect's parameters in `p` (the inverse of [`Effect::apply`]).
    pub(super) fn read(self, p: &Params) -> Vec<f64> {
        self.catalogue()
            .parameters
            .iter()
            .map(|q| (q.read)(p))
            .collect()
    }

    /// Its parameters `theta` by name, the non-finite ones left out (as the JSON lists
    /// them).
    pub(super) fn keyed(self, theta: &[f64]) -> std::collections::BTreeMap<String, f64> {
        self.parameters()
            .iter()
            .zip(theta)
            .filter(|(_, x)| x.is_finite())
            .map(|(k, x)| (k.to_string(), *x))
            .collect()
    }

    /// The one-sigma uncertainties `sigma` of its parameters by name, every one kept: a
    /// sigma the data cannot bound stays infinite or NaN, which says it is no evidence.
    pub(super) fn sigma_map(self, sigma: &[f64]) -> std::collections::BTreeMap<String, f64> {
        self.parameters()
            .iter()
            .zip(sigma)
            .map(|(k, x)| (k.to_string(), *x))
            .collect()
    }

    /// Switch the effect on in `p` with its parameters `theta`.
    pub(super) fn apply(self, p: &mut Params, theta: &[f64]) {
        let e = self.catalogue();
        e.set_enabled(p, true);
        for (q, &x) in e.parameters.iter().zip(theta) {
            (q.write)(p, x);
        }
    }

    /// The fitting bounds for `table`, lower and upper, one per parameter.
    pub(super) fn bounds(self, table: &Params) -> (Vec<f64>, Vec<f64>) {
        let ranges = self.catalogue().fit_bounds(table);
        (
            ranges.iter().map(|r| r.lower).collect(),
            ranges.iter().map(|r| r.upper).collect(),
        )
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
            [Effect::Specimen, Effect::ValveDeadband]
        );
        p.apply_effect_spec("specimen:mode2.mass_kg=2e3,mode2.frequency_hz=9")
            .unwrap();
        assert_eq!(
            Effect::present_in(&p),
            [Effect::SpecimenTwoModes, Effect::ValveDeadband]
        );
        let theta = Effect::SpecimenTwoModes.read(&p);
        let keyed = Effect::SpecimenTwoModes.keyed(&theta);
        assert_eq!(keyed["mode2.frequency_hz"], 9.0);
        assert_eq!(keyed.len(), theta.len());
    }

    /// Each diagnosis effect is the catalogue entry of its name (the enum's order is the
    /// catalogue's).
    #[test]
    fn every_effect_is_its_catalogue_entry() {
        for e in EFFECTS
            .into_iter()
            .chain([Effect::SpecimenTwoModes, Effect::SpecimenThreeModes])
        {
            // the variant's own name (its JSON form) is its catalogue entry's
            let variant = serde_json::to_string(&e).unwrap();
            assert_eq!(variant, format!("\"{}\"", e.catalogue().name));
            let entry = crate::effects::by_name(e.name()).unwrap();
            let mut p = Params::trees_lab();
            let theta: Vec<f64> = e.read(&p).iter().map(|x| x * 1.1 + 0.001).collect();
            e.apply(&mut p, &theta);
            assert!(entry.is_enabled(&p));
            assert_eq!(e.read(&p), theta);
        }
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
            match e {
                Effect::Specimen | Effect::SpecimenTwoModes | Effect::SpecimenThreeModes => {
                    &["R2", "R3"]
                }
                Effect::Foundation => &["R1", "R3", "S9"],
                Effect::StickSlip => &["S1", "S2", "S4", "S5", "S7", "S8", "T1", "T3"],
                Effect::FlowSaturation | Effect::FlowAsymmetry => &["R2", "S6", "S9"],
                Effect::ValveDeadband => &["R2", "S1", "T1", "T3"],
                Effect::FrictionAsymmetry => &["S1", "S4", "T1", "T3"],
                Effect::FreePlay => &["R1", "S9"],
            }
        };
        let check = |c: &Campaign| {
            for e in EFFECTS {
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
