//! The compared channels ([`Channel`]): their names, the measured and simulated samples of
//! each, the feedback noise each carries, and [`PerChannel`], one value per channel.

use crate::campaign::{Measured, Record};
use crate::{Outputs, SensorNoise};
use std::ops::{Index, IndexMut};

/// A channel the diagnosis compares, measured against simulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Channel {
    Displacement,
    Acceleration,
    Force,
    Spool,
    ValveCommand,
}

impl Channel {
    /// Every channel, in the order of the JSON, the reports and [`PerChannel`].
    pub const ALL: [Channel; 5] = [
        Channel::Displacement,
        Channel::Acceleration,
        Channel::Force,
        Channel::Spool,
        Channel::ValveCommand,
    ];

    /// Its name in the diagnosis JSON and reports.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Displacement => "displacement",
            Channel::Acceleration => "acceleration",
            Channel::Force => "force",
            Channel::Spool => "spool",
            Channel::ValveCommand => "valve_command",
        }
    }

    /// The channel called `name` ([`Channel::name`]).
    pub fn named(name: &str) -> Option<Channel> {
        Channel::ALL.into_iter().find(|ch| ch.name() == name)
    }

    /// The campaign's channel it compares.
    pub fn recorded(self) -> Measured {
        match self {
            Channel::Displacement => Measured::Displacement,
            Channel::Acceleration => Measured::Acceleration,
            Channel::Force => Measured::Force,
            Channel::Spool => Measured::Spool,
            Channel::ValveCommand => Measured::ValveCommand,
        }
    }

    /// Its samples in a record (None when the record lacks it).
    pub fn measured(self, r: &Record) -> Option<&[f64]> {
        r.measured(self.recorded())
    }

    /// Its reading in simulated outputs.
    pub fn simulated(self, o: &Outputs) -> f64 {
        match self {
            Channel::Displacement => o.displacement_m,
            Channel::Acceleration => o.acceleration_m_s2,
            Channel::Force => o.actuator_force_n,
            Channel::Spool => o.spool_position,
            Channel::ValveCommand => o.valve_command,
        }
    }

    /// The noise sample on it that the feedback saw (none on the spool and command).
    pub fn fed_back(self, n: &SensorNoise) -> f64 {
        match self {
            Channel::Displacement => n.displacement_m,
            Channel::Acceleration => n.acceleration_m_s2,
            Channel::Force => n.force_n,
            Channel::Spool | Channel::ValveCommand => 0.0,
        }
    }
}

/// One value per [`Channel`], held in the order of [`Channel::ALL`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PerChannel<T>([T; 5]);

impl<T> PerChannel<T> {
    /// The value `f(ch)` for every channel.
    pub fn from_fn(mut f: impl FnMut(Channel) -> T) -> Self {
        PerChannel(Channel::ALL.map(&mut f))
    }

    /// `x` for every channel.
    pub fn filled(x: T) -> Self
    where
        T: Clone,
    {
        PerChannel::from_fn(|_| x.clone())
    }

    pub fn map<U>(self, f: impl FnMut(T) -> U) -> PerChannel<U> {
        PerChannel(self.0.map(f))
    }

    /// Every channel with its value, in order.
    pub fn iter(&self) -> impl Iterator<Item = (Channel, &T)> {
        Channel::ALL.into_iter().zip(&self.0)
    }

    /// Every value, in channel order.
    pub fn values(&self) -> impl Iterator<Item = &T> {
        self.0.iter()
    }
}

/// The values in the order of [`Channel::ALL`].
impl<T> From<[T; 5]> for PerChannel<T> {
    fn from(values: [T; 5]) -> Self {
        PerChannel(values)
    }
}

impl<T> Index<Channel> for PerChannel<T> {
    type Output = T;
    fn index(&self, ch: Channel) -> &T {
        &self.0[ch as usize]
    }
}

impl<T> IndexMut<Channel> for PerChannel<T> {
    fn index_mut(&mut self, ch: Channel) -> &mut T {
        &mut self.0[ch as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `ALL` is the declaration order, which indexes the map, and names round-trip.
    #[test]
    fn channels_index_their_map_in_order_and_names_round_trip() {
        let m = PerChannel::from_fn(|ch| ch.name());
        for (k, (ch, name)) in m.iter().enumerate() {
            assert_eq!(ch, Channel::ALL[k]);
            assert_eq!(m[ch], *name);
            assert_eq!(Channel::named(name), Some(ch));
        }
        assert_eq!(Channel::named("pressure"), None);
        assert_eq!(m.map(str::len)[Channel::ValveCommand], 13);
    }
}
