//! campaign.toml's controller gains: `[controller]` and a test's `controller = { ... }`
//! override, each gain within its magnitude bound; an unknown gain is an error.

use super::toml_values::*;
use super::*;

/// Largest magnitude of each TVC gain (spec section 2, u normalised to [-1, 1]): the gain
/// that opens the valve fully for an error of 1 nm, 1 nm/s, 1 nm/s^2 or 1 micro-newton,
/// a thousand times finer than any table's sensors resolve. The sign is not restricted
/// here: an unstable loop is reported by the stability check, not as a format error.
pub(super) const GAIN_LIMITS: [(&str, f64, &str); 6] = [
    ("kp", 1e9, "1/m"),
    ("kv", 1e9, "s/m"),
    ("ka", 1e9, "s^2/m"),
    ("fv", 1e9, "s/m"),
    ("fa", 1e9, "s^2/m"),
    ("kdp", 1e6, "1/N"),
];

/// The magnitude bound of gain `key`.
pub(super) fn gain_check(key: &str) -> Bound {
    let (_, max, unit) = GAIN_LIMITS
        .iter()
        .find(|(k, _, _)| *k == key)
        .copied()
        .unwrap_or(("", f64::MAX, ""));
    Bound {
        min: -max,
        max,
        unit,
    }
}

pub(super) const GAINS: [&str; 6] = ["kp", "kv", "ka", "fv", "fa", "kdp"];

/// `[controller]`: every gain required, finite; unknown gains are errors.
/// `[controller]`: each gain given is checked; one not given is unknown
/// (campaign-format.md).
pub(super) fn read_controller(
    lines: &Lines,
    c: &Spanned<RawTable>,
) -> Result<ControllerOverride, CampaignError> {
    let off = c.span().start;
    let t = c.get_ref();
    for (k, _) in t.iter() {
        if !GAINS.contains(&k.get_ref().as_str()) {
            return Err(lines.err(
                Some(k.span().start),
                None,
                Some(&format!("controller.{}", k.get_ref())),
                format!(
                    "unknown controller gain; the gains are {}",
                    GAINS.join(", ")
                ),
            ));
        }
    }
    let _ = off;
    let g = |key: &str| -> Result<Option<f64>, CampaignError> {
        lookup(t, key)
            .map(|v| {
                number(lines, v, None, key, gain_check(key))
                    .map_err(|e| rename_key(e, &format!("controller.{key}")))
            })
            .transpose()
    };
    Ok(ControllerOverride {
        kp: g("kp")?,
        kv: g("kv")?,
        ka: g("ka")?,
        fv: g("fv")?,
        fa: g("fa")?,
        kdp: g("kdp")?,
    })
}

pub(super) fn rename_key(e: CampaignError, new_key: &str) -> CampaignError {
    match e {
        CampaignError::Toml {
            file,
            line,
            test,
            message,
            ..
        } => CampaignError::Toml {
            file,
            line,
            test,
            key: Some(new_key.to_string()),
            message,
        },
        other => other,
    }
}

/// A test's `controller = { ... }` override.
pub(super) fn read_override(
    lines: &Lines,
    v: &Spanned<toml::Value>,
    test: &str,
) -> Result<ControllerOverride, CampaignError> {
    let off = Some(v.span().start);
    let toml::Value::Table(t) = v.get_ref() else {
        return Err(lines.err(
            off,
            Some(test),
            Some("controller"),
            format!(
                "expected a table of gains like {{ fv = 0.0 }}, found {}",
                type_name(v.get_ref())
            ),
        ));
    };
    let mut o = ControllerOverride::default();
    for (k, val) in t {
        let key = format!("controller.{k}");
        let x = as_number(val).ok_or_else(|| {
            lines.err(
                off,
                Some(test),
                Some(&key),
                format!("expected a number, found {}", type_name(val)),
            )
        })?;
        if let Some(rule) = broken(x, gain_check(k)) {
            return Err(lines.err(off, Some(test), Some(&key), rule));
        }
        let slot = match k.as_str() {
            "kp" => &mut o.kp,
            "kv" => &mut o.kv,
            "ka" => &mut o.ka,
            "fv" => &mut o.fv,
            "fa" => &mut o.fa,
            "kdp" => &mut o.kdp,
            _ => {
                return Err(lines.err(
                    off,
                    Some(test),
                    Some(&key),
                    format!(
                        "unknown controller gain; the gains are {}",
                        GAINS.join(", ")
                    ),
                ))
            }
        };
        *slot = Some(x);
    }
    Ok(o)
}
