//! An effect's parameter values by key (spec section 7): what crosses the diagnosis'
//! functions instead of a positional vector. Only the optimisers' boundaries
//! (`FreeLayout` in `candidate_fit.rs`, the refinement in `baseline.rs`, the free play's
//! polish) lay the values out in a vector, through [`EffectValues::from_layout`] and
//! [`EffectValues::layout`].

use super::effect::Effect;
use crate::params::Params;
use std::collections::BTreeMap;

/// The values of every fitted parameter of one effect ([`Effect::parameters`]), read and
/// written by key.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectValues {
    effect: Effect,
    /// In the catalogue's declaration order (private: the keys are the interface).
    values: Vec<f64>,
}

impl EffectValues {
    /// `effect` with the values `pairs` (`(key, value)`), every parameter given once.
    ///
    /// # Panics
    /// When a key is not the effect's, is given twice, or a parameter is missing: a
    /// programming error, never the data's.
    pub fn new(effect: Effect, pairs: &[(&str, f64)]) -> EffectValues {
        let keys = effect.parameters();
        let mut values = vec![None; keys.len()];
        for &(key, value) in pairs {
            let k = position(effect, key);
            assert!(values[k].is_none(), "{}.{key} given twice", effect.name());
            values[k] = Some(value);
        }
        let values = keys
            .iter()
            .zip(values)
            .map(|(key, v)| v.unwrap_or_else(|| panic!("{}.{key} not given", effect.name())))
            .collect();
        EffectValues { effect, values }
    }

    /// The effect's parameters in `p` (the inverse of [`EffectValues::apply`]).
    pub fn read(effect: Effect, p: &Params) -> EffectValues {
        let values = effect
            .catalogue()
            .parameters
            .iter()
            .map(|q| (q.read)(p))
            .collect();
        EffectValues { effect, values }
    }

    /// The values laid out in the effect's declaration order, as an optimiser's vector
    /// holds them: for the optimisers' boundaries only.
    ///
    /// # Panics
    /// When `layout` does not hold one value per parameter.
    pub(super) fn from_layout(effect: Effect, layout: &[f64]) -> EffectValues {
        assert_eq!(layout.len(), effect.parameters().len(), "{}", effect.name());
        EffectValues {
            effect,
            values: layout.to_vec(),
        }
    }

    /// The values in the effect's declaration order ([`EffectValues::from_layout`]).
    pub(super) fn layout(&self) -> &[f64] {
        &self.values
    }

    pub fn effect(&self) -> Effect {
        self.effect
    }

    /// The value of `key`.
    ///
    /// # Panics
    /// When the effect has no parameter `key`.
    pub fn get(&self, key: &str) -> f64 {
        self.values[position(self.effect, key)]
    }

    /// The value of `key`, `None` when the effect has no such parameter.
    pub fn try_get(&self, key: &str) -> Option<f64> {
        let k = self.effect.parameters().iter().position(|n| *n == key)?;
        Some(self.values[k])
    }

    /// Set `key` to `value`.
    ///
    /// # Panics
    /// When the effect has no parameter `key`.
    pub fn set(&mut self, key: &str, value: f64) {
        let k = position(self.effect, key);
        self.values[k] = value;
    }

    /// `(key, value)` of every parameter, in declaration order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        self.effect
            .parameters()
            .into_iter()
            .zip(self.values.iter().copied())
    }

    /// Switch the effect on in `p` with these values.
    pub fn apply(&self, p: &mut Params) {
        let e = self.effect.catalogue();
        e.set_enabled(p, true);
        for (q, &x) in e.parameters.iter().zip(&self.values) {
            (q.write)(p, x);
        }
    }

    /// The values by name, the non-finite ones left out (as the JSON lists them).
    pub fn finite_map(&self) -> BTreeMap<String, f64> {
        self.iter()
            .filter(|(_, x)| x.is_finite())
            .map(|(k, x)| (k.to_string(), x))
            .collect()
    }

    /// The values by name, every one kept (an uncertainty the data cannot bound stays
    /// infinite or NaN, which says it is no evidence).
    pub fn map(&self) -> BTreeMap<String, f64> {
        self.iter().map(|(k, x)| (k.to_string(), x)).collect()
    }
}

/// The fitting range of an effect's parameters: the lower and the upper bounds, by key.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectBounds {
    pub lower: EffectValues,
    pub upper: EffectValues,
}

impl EffectBounds {
    /// The diagnosis' fitting bounds of `effect` for `table`
    /// ([`crate::effects::Effect::fit_bounds`]).
    pub fn of(effect: Effect, table: &Params) -> EffectBounds {
        let ranges = effect.catalogue().fit_bounds(table);
        let side = |f: fn(&crate::effects::FitRange) -> f64| {
            EffectValues::from_layout(effect, &ranges.iter().map(f).collect::<Vec<f64>>())
        };
        EffectBounds {
            lower: side(|r| r.lower),
            upper: side(|r| r.upper),
        }
    }

    /// `(key, lower, upper)` of every parameter, in declaration order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, f64, f64)> + '_ {
        self.lower
            .iter()
            .zip(self.upper.iter())
            .map(|((k, lo), (_, hi))| (k, lo, hi))
    }
}

/// The index of `key` among `effect`'s parameters.
fn position(effect: Effect, key: &str) -> usize {
    effect
        .parameters()
        .iter()
        .position(|n| *n == key)
        .unwrap_or_else(|| panic!("effect `{}` has no parameter `{key}`", effect.name()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values are built and read by key, whatever order they are given in.
    #[test]
    fn values_are_read_by_key() {
        let e = Effect::of(&crate::effects::foundation::EFFECT);
        let v = EffectValues::new(
            e,
            &[
                ("frequency_hz", 12.0),
                ("damping_ratio", 0.05),
                ("mass_kg", 2e5),
            ],
        );
        assert_eq!(v.get("mass_kg"), 2e5);
        assert_eq!(v.try_get("gap_m"), None);
        let keys: Vec<&str> = v.iter().map(|(k, _)| k).collect();
        assert_eq!(keys, e.parameters());
        let mut p = Params::trees_lab();
        v.apply(&mut p);
        assert_eq!(EffectValues::read(e, &p), v);
    }

    #[test]
    #[should_panic(expected = "given twice")]
    fn a_key_given_twice_is_refused() {
        EffectValues::new(
            Effect::of(&crate::effects::friction_asymmetry::EFFECT),
            &[("ratio", 1.0), ("ratio", 2.0)],
        );
    }

    #[test]
    #[should_panic(expected = "no parameter")]
    fn a_key_of_another_effect_is_refused() {
        EffectValues::new(
            Effect::of(&crate::effects::friction_asymmetry::EFFECT),
            &[("gap_m", 1.0)],
        );
    }

    #[test]
    #[should_panic(expected = "not given")]
    fn a_missing_key_is_refused() {
        EffectValues::new(
            Effect::of(&crate::effects::stick_slip::EFFECT),
            &[("static_ratio", 2.0)],
        );
    }
}
