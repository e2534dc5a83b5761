#![allow(dead_code)]
//! The UTFSM recordings (`tests/data/utfsm`, MIT licence): an MTS actuator in displacement
//! control pushing an MR damper at 0, 0.5 and 1 A, as the DAQ exported them (volts, a
//! date column, an event note, 1 kHz), read in place through a campaign.toml that maps the
//! lab's own columns, as a user would write it.

use shaketable::campaign::format::read_campaign;
use shaketable::campaign::Campaign;

/// campaign.toml's head: how the DAQ's export is read and what its columns are. The
/// force line is added when a campaign uses the load cell.
pub const CAMPAIGN_HEAD: &str = r#"
name = "UTFSM MTS actuator with MR damper (2022)"
sample_rate_hz = 1000.0

[read]
delimiter = ","
header_line = 7

[columns]
ref_displacement_m = { column = "CHANNEL2", scale = 0.01 }   # 10 mm/V
displacement_m = { column = "CHANNEL0", scale = 0.01 }       # 10 mm/V
"#;

/// The load cell: 1 tf/V, read with the sign of the damper's push (the force then does
/// positive net work on the motion, as a dissipating device's must).
pub const FORCE_LINE: &str = "force_n = { column = \"CHANNEL1\", scale = 9806.65 }\n";

/// The recordings by current (A), the chirps of 2022-06-29 and the 15-Hz random runs of
/// 2022-05-25.
pub const CHIRP_0A: &str = "chirp_0A.txt";
pub const CHIRP_1A: &str = "chirp_1A.txt";
pub const RUN_15HZ_0A: &str = "validation_15Hz_0A.txt";
pub const RUN_15HZ_0X5A: &str = "validation_15Hz_0x5A.txt";
pub const RUN_15HZ_1A: &str = "validation_15Hz_1A.txt";

/// A campaign folder of `tests` (test name, file), every one a `record` test in
/// displacement control, with the force mapped when `force`; and the campaign read.
pub fn campaign(tests: &[(&str, &str)], force: bool) -> (tempfile::TempDir, Campaign) {
    let tmp = tempfile::tempdir().unwrap();
    let mut toml = CAMPAIGN_HEAD.to_string();
    if force {
        toml.push_str(FORCE_LINE);
    }
    for (name, file) in tests {
        let data = format!("{}/tests/data/utfsm/{file}", env!("CARGO_MANIFEST_DIR"));
        std::fs::copy(data, tmp.path().join(file)).unwrap();
        toml.push_str(&format!(
            "\n[[test]]\nname = \"{name}\"\nfile = \"{file}\"\nkind = \"record\"\ncontrol = \"displacement\"\n"
        ));
    }
    std::fs::write(tmp.path().join("campaign.toml"), toml).unwrap();
    let c = read_campaign(tmp.path()).unwrap();
    (tmp, c)
}
