//! What the diagnosis knows of each effect beyond its catalogue entry (spec section 7):
//! its starts, the start read off the data, which fit it takes, the frequency whose
//! starts lie in different valleys, what its starts take out of the identified baseline. One row per effect in [`TABLE`]: adding an effect to
//! the catalogue ([`crate::effects`]) adds one row here (a unit test checks that the rows
//! cover the catalogue exactly, by name).

use super::direction_starts::{flow_ratio_start, friction_ratio_start};
use super::effect::Effect;
use super::effect_values::EffectValues;
use super::free_play_start::free_play_start;
use super::mode_starts::{carried_mode_start, higher_mode_starts, specimen_starts};
use super::starts::{
    asymmetry_grid, deadband_grid, flow_limit_start, foundation_start, foundation_starts,
    one_value, stick_slip_grid, ROD_MASS_FRACTION,
};
use crate::campaign::Campaign;
use crate::effects;
use crate::params::Params;

/// How an effect is fitted ([`super::candidates::fit_candidate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum FitKind {
    /// Output-error least squares with the baseline's refined parameters free, from its
    /// starts ([`super::candidate_fit`]).
    OutputError,
    /// On the predictive score from the friction-velocity curve or a grid
    /// ([`super::stick_slip`]): its chatter grows out of the sensor noise.
    StickSlip,
    /// On the predictive score from the gap read off the reversals only
    /// ([`super::free_play_fit`]): its bounces inside the gap are chaotic.
    FreePlay,
}

/// What the identified baseline already holds of an effect, which a start of its
/// output-error fit takes out ([`super::candidate_fit`]): the baseline was identified
/// without it and bent to absorb it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum TakesOut {
    Nothing,
    /// The identified table mass holds the specimen's newest mode's mass at low frequency.
    NewestModeMass,
    /// The identified oil column is the oil and the foundation's spring in series.
    FoundationSpring,
}

/// What an effect's starts are read from: the effect, the campaign, the base they start
/// on, and the start read off the data ([`Row::informed`]), which may seed the spread.
pub(super) struct StartsFrom<'a> {
    pub effect: Effect,
    pub c: &'a Campaign,
    pub base: &'a Params,
    pub informed: Option<&'a EffectValues>,
}

/// One effect as the diagnosis fits it.
pub(super) struct Row {
    /// Its catalogue entry: parameters, fitting ranges, signature tests, JSON name.
    pub catalogue: &'static effects::Effect,
    /// A specimen's modes (1 for the catalogue's own entry), `None` for the other effects.
    pub specimen_modes: Option<usize>,
    pub fit: FitKind,
    /// Its starting points (physically informed where the data allows; small grids).
    pub starts: fn(&StartsFrom) -> Vec<EffectValues>,
    /// Its start read off the data, fitted whatever the screening says (the caller's
    /// `informed` is `None` here); `None` when it has no such reading.
    pub informed: Option<fn(&StartsFrom) -> Option<EffectValues>>,
    /// The key of the resonance frequency whose starts lie in different valleys of the
    /// fit ([`super::starts::keep_each_frequency`]): the foundation's, and a specimen's
    /// newest mode's (the first mode's starts lie at one frequency when read off the
    /// apparent mass, on a blind grid without it).
    pub valley_frequency: Option<&'static str>,
    /// What its starts take out of the identified baseline.
    pub takes_out: TakesOut,
}

/// Every effect the diagnosis fits: the catalogue's, in any order (the search takes the
/// catalogue's order: [`Effect::search_order`]), and the specimen with a second and a
/// third mode, each fitted on a candidate with one mode fewer ([`Effect::next_mode`]).
pub(super) static TABLE: [Row; 10] = [
    Row {
        catalogue: &effects::specimen::EFFECT,
        specimen_modes: Some(1),
        fit: FitKind::OutputError,
        starts: |s| specimen_starts(s.c, s.base),
        informed: None,
        valley_frequency: Some("frequency_hz"),
        takes_out: TakesOut::NewestModeMass,
    },
    Row {
        catalogue: &effects::foundation::EFFECT,
        specimen_modes: None,
        fit: FitKind::OutputError,
        starts: |s| foundation_starts(s.base.table.mass_kg, s.informed),
        informed: Some(|s| foundation_start(s.c, s.base.table.mass_kg)),
        valley_frequency: Some("frequency_hz"),
        takes_out: TakesOut::FoundationSpring,
    },
    Row {
        catalogue: &effects::stick_slip::EFFECT,
        specimen_modes: None,
        fit: FitKind::StickSlip,
        starts: |_| stick_slip_grid(),
        informed: None,
        valley_frequency: None,
        takes_out: TakesOut::Nothing,
    },
    Row {
        catalogue: &effects::flow_saturation::EFFECT,
        specimen_modes: None,
        fit: FitKind::OutputError,
        starts: |s| vec![one_value(s.effect, flow_limit_start(s.c, s.base))],
        informed: None,
        valley_frequency: None,
        takes_out: TakesOut::Nothing,
    },
    Row {
        catalogue: &effects::valve_deadband::EFFECT,
        specimen_modes: None,
        fit: FitKind::OutputError,
        starts: |s| deadband_grid(s.effect),
        informed: None,
        valley_frequency: None,
        takes_out: TakesOut::Nothing,
    },
    Row {
        catalogue: &effects::friction_asymmetry::EFFECT,
        specimen_modes: None,
        fit: FitKind::OutputError,
        // a grid either side of symmetry; the direction split adds its own start
        starts: |s| asymmetry_grid(s.effect),
        informed: Some(|s| friction_ratio_start(s.c, s.base).map(|r| one_value(s.effect, r))),
        valley_frequency: None,
        takes_out: TakesOut::Nothing,
    },
    Row {
        catalogue: &effects::flow_asymmetry::EFFECT,
        specimen_modes: None,
        fit: FitKind::OutputError,
        starts: |s| asymmetry_grid(s.effect),
        informed: Some(|s| flow_ratio_start(s.c).map(|r| one_value(s.effect, r))),
        valley_frequency: None,
        takes_out: TakesOut::Nothing,
    },
    Row {
        catalogue: &effects::free_play::EFFECT,
        specimen_modes: None,
        fit: FitKind::FreePlay,
        // fitted from the gap read off the data alone ([`super::free_play_fit`])
        starts: |_| Vec::new(),
        informed: Some(|s| free_play_start(s.c, s.base, ROD_MASS_FRACTION * s.base.table.mass_kg)),
        valley_frequency: None,
        takes_out: TakesOut::Nothing,
    },
    Row {
        catalogue: &effects::specimen::TWO_MODES,
        specimen_modes: Some(2),
        fit: FitKind::OutputError,
        starts: |s| higher_mode_starts(s.effect, s.c, s.base),
        informed: Some(|s| carried_mode_start(s.effect, s.c, s.base)),
        valley_frequency: Some("mode2.frequency_hz"),
        takes_out: TakesOut::NewestModeMass,
    },
    Row {
        catalogue: &effects::specimen::THREE_MODES,
        specimen_modes: Some(3),
        fit: FitKind::OutputError,
        starts: |s| higher_mode_starts(s.effect, s.c, s.base),
        informed: Some(|s| carried_mode_start(s.effect, s.c, s.base)),
        valley_frequency: Some("mode3.frequency_hz"),
        takes_out: TakesOut::NewestModeMass,
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Every catalogue effect has its row, once, and every row is a catalogue effect
    /// (the specimen's further modes by their own entries).
    #[test]
    fn the_table_covers_the_catalogue_exactly() {
        let own: Vec<&str> = TABLE
            .iter()
            .filter(|r| r.specimen_modes.unwrap_or(1) == 1)
            .map(|r| r.catalogue.name)
            .collect();
        let catalogue: Vec<&str> = effects::CATALOGUE.iter().map(|e| e.name).collect();
        let mut sorted = own.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), own.len(), "a row twice: {own:?}");
        let mut expected = catalogue.clone();
        expected.sort_unstable();
        assert_eq!(sorted, expected);
        // the further modes are the specimen's, numbered on from 2
        let further: Vec<(&str, Option<usize>)> = TABLE
            .iter()
            .filter(|r| r.specimen_modes.unwrap_or(1) > 1)
            .map(|r| (r.catalogue.name, r.specimen_modes))
            .collect();
        assert_eq!(further, [("specimen", Some(2)), ("specimen", Some(3))]);
    }

    /// A valley frequency is one of its effect's fitted parameters.
    #[test]
    fn the_valley_frequencies_are_parameters() {
        for r in &TABLE {
            if let Some(key) = r.valley_frequency {
                assert!(r.catalogue.parameters.iter().any(|q| q.key == key), "{key}");
            }
        }
    }
}
