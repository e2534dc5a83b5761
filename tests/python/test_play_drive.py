"""A drive from `shaketable drive` played through ShakeTable.fmu in fmpy (issue 19, part 5):
with the table's parameters as start values it gives exactly what the tool predicted;
with the specimen as a separate body in the master, coupled through `external_force`,
within the coupling's error."""
import os
import subprocess

import numpy as np

from conftest import ROOT
from play_drive import play, read_csv, start_values

BINARY = os.path.join(ROOT, "target", "release", "shaketable")
ELCENTRO = os.path.join(ROOT, "tests", "data", "records", "elcentro_1940_ns_g.txt")
SPECIMEN = (25000.0, 5.0, 0.02)


def run(*args):
    subprocess.run([BINARY, *args], check=True, capture_output=True, text=True)


def test_a_drive_plays_through_the_fmu_as_predicted(fmu_path, tmp_path):
    target = tmp_path / "target.csv"
    run("record", "import", ELCENTRO, "--units", "g", "--dt", "0.01", "--scale-pga", "0.3g",
        "--rate-hz", "256", "--out", str(target))
    defaults = subprocess.run([BINARY, "params", "--defaults"], check=True, capture_output=True, text=True).stdout
    params = tmp_path / "specimen.toml"
    with_specimen = defaults.replace("[specimen]\nenabled = false\nmass_kg = 10000.0\nfrequency_hz = 5.0",
                                     "[specimen]\nenabled = true\nmass_kg = 25000.0\nfrequency_hz = 5.0")
    assert with_specimen != defaults
    params.write_text(with_specimen)
    out = tmp_path / "d0"
    run("drive", "--params", str(params), "--target", str(target), "--out", str(out))
    drive = read_csv(out / "drive.csv")
    predicted = read_csv(out / "predicted.csv")
    own = play(fmu_path, drive, start_values(str(params), BINARY))
    np.testing.assert_array_equal(own[:, 0], predicted["acceleration_m_s2"])
    np.testing.assert_array_equal(own[:, 2], predicted["force_n"])
    # the specimen in the master instead: the same motion within the coupling's error
    bare = start_values(None, BINARY)
    cosim = play(fmu_path, drive, bare, SPECIMEN)
    a = predicted["acceleration_m_s2"]
    rms = np.sqrt(np.mean((cosim[:, 0] - a) ** 2)) / np.sqrt(np.mean(a ** 2))
    assert rms < 0.02, rms
