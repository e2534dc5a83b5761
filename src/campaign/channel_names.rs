//! Channel names that look like a misspelled project channel (`displacment_m` for
//! `displacement_m`). campaign-format.md keeps every further channel under its own name, so
//! such a name is no error: it is read and kept, and the channel it was meant to be is
//! missing (identification then runs without it). [`Campaign::near_misses`] names each
//! one with the channel it probably means; the command line prints them as warnings.

use super::format::{REQUIRED_CHANNELS, SPOOL_CHANNEL};
use super::provenance::Source;
use super::Campaign;

/// Most edits (insertions, deletions, substitutions, swaps of neighbours) between a
/// `[columns]` key and a project channel for the key to count as a misspelling of it: two,
/// and at most one per four characters of the channel, so that short names (`time_s`,
/// `force_n`) need a closer match than long ones (`displacement_m`) before a key is
/// doubted. A file's own column names are the lab's choice (`Time_ms` is one edit from
/// `time_s` and means milliseconds): only a difference of case (`Force_N`) is named.
const MAX_EDITS: usize = 2;
const CHARACTERS_PER_EDIT: usize = 4;

/// Where a suspicious name comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum NameOrigin {
    /// A `[columns]` key (campaign-wide or a test's) mapping file column `column`.
    ColumnsKey { column: String },
    /// A column of the file kept under its own name (no mapping names it).
    FileColumn,
}

/// A channel name that is probably a misspelling of project channel `channel`, which the
/// tests `tests` do not read from their files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NearMiss {
    pub name: String,
    pub channel: &'static str,
    pub edits: usize,
    pub origin: NameOrigin,
    pub tests: Vec<String>,
}

impl std::fmt::Display for NearMiss {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let edits = match self.edits {
            0 => "differs only in case from".to_string(),
            1 => "is 1 edit from".to_string(),
            n => format!("is {n} edits from"),
        };
        let tests = self
            .tests
            .iter()
            .map(|t| format!("`{t}`"))
            .collect::<Vec<_>>()
            .join(", ");
        let (s, es) = if self.tests.len() == 1 {
            ("", "es")
        } else {
            ("s", "")
        };
        let (name, channel) = (&self.name, self.channel);
        match &self.origin {
            NameOrigin::ColumnsKey { column } => write!(
                f,
                "[columns] key `{name}` (column `{column}`) is no channel name but {edits} \
                 `{channel}`, which test{s} {tests} do{es} not read: a misspelling? It is kept \
                 as a further channel under its own name; rename the key to read it as `{channel}`"
            ),
            NameOrigin::FileColumn => write!(
                f,
                "file column `{name}` {edits} `{channel}`, which test{s} {tests} do{es} not \
                 read: it is kept as a further channel under its own name; map it in [columns] \
                 (`{channel} = \"{name}\"`) to read it as `{channel}`"
            ),
        }
    }
}

/// The project channels a name may be a misspelling of.
fn project_channels() -> impl Iterator<Item = &'static str> {
    REQUIRED_CHANNELS
        .iter()
        .copied()
        .chain(std::iter::once(SPOOL_CHANNEL))
}

/// The project channel `name` is probably a misspelling of, with the edits between them
/// (case ignored); `None` for a project channel itself or a name far from every one.
pub fn near_miss(name: &str) -> Option<(&'static str, usize)> {
    if project_channels().any(|c| c == name) {
        return None;
    }
    let lower = name.to_lowercase();
    project_channels()
        .map(|c| (c, edit_distance(&lower, c)))
        .filter(|&(c, d)| d <= MAX_EDITS && d * CHARACTERS_PER_EDIT <= c.len())
        .min_by_key(|&(_, d)| d)
}

/// Edits between `a` and `b`: insertions, deletions, substitutions and swaps of two
/// neighbours (optimal string alignment, strsim's), by character.
pub fn edit_distance(a: &str, b: &str) -> usize {
    strsim::osa_distance(a, b)
}

impl Campaign {
    /// The further channels whose names are probably misspelled project channels that
    /// their tests do not read from a column (missing, or computed / made from the rate),
    /// one entry per name and origin with every test concerned.
    pub fn near_misses(&self) -> Vec<NearMiss> {
        let mut out: Vec<NearMiss> = Vec::new();
        for (spec, record) in self.info.tests.iter().zip(&self.records) {
            let sources = self.sources.get(&spec.name);
            let read_from_file = |channel: &str| {
                sources
                    .and_then(|s| s.of(channel))
                    .is_some_and(|s| matches!(s, Source::Column { .. }))
            };
            for (name, _) in &record.extra {
                let Some((channel, edits)) = near_miss(name) else {
                    continue;
                };
                if read_from_file(channel) {
                    continue;
                }
                let origin = match sources.and_then(|s| s.of(name)) {
                    Some(Source::Column { column, .. }) if column != name => {
                        NameOrigin::ColumnsKey {
                            column: column.clone(),
                        }
                    }
                    _ => NameOrigin::FileColumn,
                };
                if origin == NameOrigin::FileColumn && edits > 0 {
                    continue;
                }
                match out
                    .iter_mut()
                    .find(|m| m.name == *name && m.origin == origin)
                {
                    Some(m) => m.tests.push(spec.name.clone()),
                    None => out.push(NearMiss {
                        name: name.clone(),
                        channel,
                        edits,
                        origin,
                        tests: vec![spec.name.clone()],
                    }),
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_count_insertions_deletions_substitutions_and_swaps() {
        assert_eq!(edit_distance("displacment_m", "displacement_m"), 1);
        assert_eq!(edit_distance("dispalcement_m", "displacement_m"), 1);
        assert_eq!(edit_distance("displacement_mm", "displacement_m"), 1);
        assert_eq!(edit_distance("forse_kn", "force_n"), 2);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("abc", "abc"), 0);
    }

    #[test]
    fn near_misses_of_project_channels_only() {
        assert_eq!(near_miss("displacment_m"), Some(("displacement_m", 1)));
        assert_eq!(near_miss("Displacement_m"), Some(("displacement_m", 0)));
        assert_eq!(
            near_miss("acceleration_m_s"),
            Some(("acceleration_m_s2", 1))
        );
        assert_eq!(near_miss("tme_s"), Some(("time_s", 1)));
        assert_eq!(near_miss("spool_positon"), Some(("spool_position", 1)));
        // a project channel, and a lab's own names, are not doubted
        for name in [
            "displacement_m",
            "pressure_a_pa",
            "velocity_m_s",
            "Sample Number",
            "temp_c",
            "force_kn2",
        ] {
            assert_eq!(near_miss(name), None, "{name}");
        }
        // a short channel allows one edit only: `frc_kn` is a lab's name, not `force_n`
        assert_eq!(near_miss("forc_n"), Some(("force_n", 1)));
        assert_eq!(near_miss("frc_kn"), None);
    }
}
