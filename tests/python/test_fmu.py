"""The FMU as fmpy sees it: validation, simulation, the table TF measured through it,
parameters baked in by build_fmu.sh --params, and the specimen co-simulation."""
import os
import subprocess

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

import cosim_specimen
import fmu_frf
from conftest import ROOT


def test_validate_fmu_finds_no_problem(fmu_path):
    assert validate_fmu(fmu_path) == []


def test_simulate_fmu_with_validation_runs(fmu_path):
    t = np.arange(0, 2, 1 / 512)
    w = 2 * np.pi * 2
    sig = np.zeros(len(t), dtype=[("time", float), ("ref_displacement", float), ("ref_velocity", float),
                                  ("ref_acceleration", float), ("external_force", float)])
    sig["time"] = t
    sig["ref_displacement"] = 0.01 * np.sin(w * t)
    sig["ref_velocity"] = 0.01 * w * np.cos(w * t)
    sig["ref_acceleration"] = -0.01 * w * w * np.sin(w * t)
    r = simulate_fmu(fmu_path, validate=True, stop_time=2.0, output_interval=1 / 512, input=sig,
                     output=["displacement", "acceleration", "actuator_force"])
    # the table follows the 10 mm, 2 Hz sine with the closed loop's gain there (about
    # 1.11 on the analytic table TF: the oil-column peak already lifts it)
    x = r["displacement"][r["time"] >= 1.0]
    assert 0.0105 < np.max(np.abs(x)) < 0.0120


def test_table_tf_through_the_fmu_has_the_papers_peak_and_phase_inversion(fmu_path):
    _, _, fig = fmu_frf.measure(fmu_path)
    assert abs(fig["peak_hz"] - 14.17) < 0.3, fig
    assert fig["phase_drop_deg"] > 110, fig
    assert abs(fig["steepest_hz"] - fig["peak_hz"]) < 0.3, fig
    assert 0.9 <= fig["low_frequency_gain"] <= 1.2, fig


def test_doubling_the_mass_through_the_fmu_moves_the_peak_to_10_hz(fmu_path):
    _, _, fig = fmu_frf.measure(fmu_path, {"table.mass": 2 * 41258.0})
    assert abs(fig["peak_hz"] - 10.0) < 0.4, fig


def test_parameter_file_is_baked_in_as_start_values(tmp_path):
    params = tmp_path / "lab.toml"
    params.write_text("[table]\nmass_kg = 60000.0\n")
    out = tmp_path / "lab.fmu"
    subprocess.run(["bash", os.path.join(ROOT, "scripts", "build_fmu.sh"), "--params", str(params), "--out", str(out)],
                   check=True, capture_output=True)
    md = read_model_description(str(out))
    mass = next(v for v in md.modelVariables if v.name == "table.mass")
    assert float(mass.start) == 60000.0
    assert validate_fmu(str(out)) == []
    # and the binary starts from it: the peak moves to 14.2 * sqrt(41258/60000) Hz
    _, _, fig = fmu_frf.measure(str(out), duration=32.0)
    assert abs(fig["peak_hz"] - 14.27 * np.sqrt(41258 / 60000)) < 0.4, fig


def test_specimen_cosimulation_matches_the_models_own_specimen(fmu_path):
    co, internal = cosim_specimen.compare(fmu_path, step=1 / 1024, duration=32.0)
    for k in ("rms_acceleration", "peak_hz", "resonance_hz", "notch_hz"):
        assert co[k] == pytest.approx(internal[k], rel=0.02), k
    # the specimen really is there: its resonance/anti-resonance pair brackets 5 Hz
    assert internal["resonance_hz"] < 5.2 and internal["notch_hz"] > 4.8
