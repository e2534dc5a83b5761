//! Writing records and campaign.toml (floats shortest round-trip).

use super::*;
use crate::campaign::Measured;

/// The channels of a record in file order: time and reference, the measured channels it
/// has, extras.
pub(super) fn channels(record: &Record) -> Vec<(&str, &[f64])> {
    let mut c: Vec<(&str, &[f64])> = vec![
        ("time_s", &record.time_s),
        ("ref_displacement_m", &record.ref_displacement_m),
        ("ref_velocity_m_s", &record.ref_velocity_m_s),
        ("ref_acceleration_m_s2", &record.ref_acceleration_m_s2),
    ];
    // the measured channels the test recorded, in the format's order
    for m in [
        Measured::ValveCommand,
        Measured::Spool,
        Measured::Displacement,
        Measured::Acceleration,
        Measured::Force,
    ] {
        if let Some(x) = record.measured(m) {
            c.push((m.name(), x));
        }
    }
    for (n, v) in &record.extra {
        c.push((n.as_str(), v));
    }
    c
}

/// The CSV text of a record (header + one row per sample, ryu floats).
pub fn record_to_csv(record: &Record, file: &str) -> Result<Vec<u8>, CampaignError> {
    let cols = channels(record);
    let n = record.len();
    let invalid = |message: String| CampaignError::Invalid {
        file: file.to_string(),
        message,
    };
    if n == 0 {
        return Err(invalid("empty record: no samples to write".to_string()));
    }
    let mut seen: Vec<&str> = Vec::with_capacity(cols.len());
    for (name, col) in &cols {
        if col.len() != n {
            return Err(invalid(format!(
                "channel `{name}` has {} samples but time_s has {n}",
                col.len()
            )));
        }
        if name.is_empty() || name.contains([',', '\n', '\r', '"']) || name.starts_with('#') {
            return Err(invalid(format!(
                "channel name `{name}` cannot be written in a CSV header"
            )));
        }
        if seen.contains(name) {
            return Err(invalid(format!("channel `{name}` appears twice")));
        }
        seen.push(name);
    }
    let mut out = Vec::with_capacity(n * cols.len() * 22 + 256);
    out.extend_from_slice(seen.join(",").as_bytes());
    out.push(b'\n');
    let mut buf = ryu::Buffer::new();
    for k in 0..n {
        for (j, (name, col)) in cols.iter().enumerate() {
            let v = col[k];
            if !v.is_finite() {
                return Err(invalid(format!(
                    "channel `{name}` sample {k} (would be line {}) is {v}: not writable",
                    k + 2
                )));
            }
            if j > 0 {
                out.push(b',');
            }
            out.extend_from_slice(buf.format_finite(v).as_bytes());
        }
        out.push(b'\n');
    }
    Ok(out)
}

/// Write one record as a campaign-format CSV.
pub fn write_record(record: &Record, path: &Path) -> Result<(), CampaignError> {
    let file = display(path);
    let bytes = record_to_csv(record, &file)?;
    write_bytes(path, &bytes)
}

/// Written atomically, never through a symlink ([`crate::output::atomic_write`]).
pub(super) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), CampaignError> {
    Ok(crate::output::atomic_write(path, bytes)?)
}

pub(super) fn toml_float(x: f64) -> String {
    let mut b = ryu::Buffer::new();
    b.format(x).to_string()
}

pub(super) fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// campaign.toml text for `info` (floats written shortest round-trip).
pub fn campaign_toml_string(info: &CampaignInfo) -> String {
    let mut s = String::new();
    s.push_str("# Campaign description (shared/spec/campaign-format.md).\n");
    s.push_str(&format!("name = {}\n", toml_string(&info.name)));
    s.push_str(&format!(
        "sample_rate_hz = {}\n\n",
        toml_float(info.sample_rate_hz)
    ));
    // the keys the campaign knows (an unknown one stays unwritten: unknown when read)
    let g = &info.geometry;
    s.push_str("[geometry]\n");
    for (k, v) in [
        ("piston_area_m2", g.piston_area_m2),
        ("total_oil_volume_m3", g.total_oil_volume_m3),
        ("supply_pressure_pa", g.supply_pressure_pa),
        ("flow_gain_m3_s", g.flow_gain_m3_s),
    ] {
        if let Some(v) = v {
            s.push_str(&format!("{k} = {}\n", toml_float(v)));
        }
    }
    s.push('\n');
    let c = &info.controller;
    s.push_str("[controller]\n");
    for (k, v) in [
        ("kp", c.kp),
        ("kv", c.kv),
        ("ka", c.ka),
        ("fv", c.fv),
        ("fa", c.fa),
        ("kdp", c.kdp),
    ] {
        if let Some(v) = v {
            s.push_str(&format!("{k} = {}\n", toml_float(v)));
        }
    }
    for t in &info.tests {
        s.push_str("\n[[test]]\n");
        s.push_str(&format!("name = {}\n", toml_string(&t.name)));
        s.push_str(&format!("file = {}\n", toml_string(&t.file)));
        let kind = match t.kind {
            TestKind::Random => "random",
            TestKind::Sine => "sine",
            TestKind::Triangle => "triangle",
            TestKind::Record => "record",
        };
        let control = match t.control {
            Control::Displacement => "displacement",
            Control::Acceleration => "acceleration",
        };
        s.push_str(&format!("kind = \"{kind}\"\ncontrol = \"{control}\"\n"));
        // the test's own rate (campaign-format.md: a test may set its own)
        if let Some(x) = t.sample_rate_hz {
            s.push_str(&format!("sample_rate_hz = {}\n", toml_float(x)));
        }
        if let Some(x) = t.rms {
            s.push_str(&format!("rms = {}\n", toml_float(x)));
        }
        if let Some([lo, hi]) = t.band_hz {
            s.push_str(&format!(
                "band_hz = [{}, {}]\n",
                toml_float(lo),
                toml_float(hi)
            ));
        }
        if let Some(x) = t.frequency_hz {
            s.push_str(&format!("frequency_hz = {}\n", toml_float(x)));
        }
        if let Some(x) = t.amplitude_m {
            s.push_str(&format!("amplitude_m = {}\n", toml_float(x)));
        }
        let o = &t.controller;
        let gains: Vec<String> = [
            ("kp", o.kp),
            ("kv", o.kv),
            ("ka", o.ka),
            ("fv", o.fv),
            ("fa", o.fa),
            ("kdp", o.kdp),
        ]
        .iter()
        .filter_map(|(k, v)| v.map(|v| format!("{k} = {}", toml_float(v))))
        .collect();
        if !gains.is_empty() {
            s.push_str(&format!("controller = {{ {} }}\n", gains.join(", ")));
        }
    }
    s
}

/// Write `info` as `dir/campaign.toml`, creating `dir` if needed.
pub fn write_campaign_info(info: &CampaignInfo, dir: &Path) -> Result<(), CampaignError> {
    std::fs::create_dir_all(dir).map_err(|source| CampaignError::Write {
        file: display(dir),
        source,
    })?;
    let path = dir.join("campaign.toml");
    let text = campaign_toml_string(info);
    // what we write must read back (catches non-finite values, bad names, duplicates)
    parse_campaign_toml(&text, &display(&path), &info.name).map_err(|e| {
        CampaignError::Invalid {
            file: display(&path),
            message: format!("would not read back: {e}"),
        }
    })?;
    write_bytes(&path, text.as_bytes())
}

/// Write a whole campaign into `dir`: campaign.toml and one CSV per test (in parallel).
/// `campaign.dir` is ignored; `campaign.records[i]` goes to `dir/info.tests[i].file`.
pub fn write_campaign(campaign: &Campaign, dir: &Path) -> Result<(), CampaignError> {
    write_campaign_parts(&campaign.info, &campaign.records, dir)
}

/// [`write_campaign`] from its parts.
pub fn write_campaign_parts(
    info: &CampaignInfo,
    records: &[Record],
    dir: &Path,
) -> Result<(), CampaignError> {
    if records.len() != info.tests.len() {
        return Err(CampaignError::Invalid {
            file: display(&dir.join("campaign.toml")),
            message: format!(
                "{} tests listed but {} records given",
                info.tests.len(),
                records.len()
            ),
        });
    }
    write_campaign_info(info, dir)?;
    let paths: Vec<PathBuf> = info.tests.iter().map(|t| dir.join(&t.file)).collect();
    for p in &paths {
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).map_err(|source| CampaignError::Write {
                file: display(parent),
                source,
            })?;
        }
    }
    records
        .par_iter()
        .zip(paths.par_iter())
        .map(|(r, p)| write_record(r, p))
        .collect::<Result<Vec<()>, CampaignError>>()?;
    Ok(())
}
