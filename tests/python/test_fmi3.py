"""The FMI 3.0 Co-Simulation FMU (issue 18, part 4): fmpy validates it, runs it, and its
results are the FMI 2.0 FMU's bit for bit (one binary, one instance code; fmpy holds the
inputs over each step in both), with the start values honoured."""
import os

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from conftest import ROOT

OUTPUTS = ["displacement", "acceleration", "actuator_force", "valve_command"]


@pytest.fixture(scope="session")
def fmu3_path(fmu_path):
    path = os.path.join(os.path.dirname(fmu_path), "ShakeTable3.fmu")
    assert os.path.exists(path), "scripts/build_fmu.sh writes ShakeTable3.fmu beside ShakeTable.fmu"
    return path


def sine(seconds=2.0):
    t = np.arange(0, seconds, 1 / 512)
    w = 2 * np.pi * 2
    sig = np.zeros(len(t), dtype=[("time", float), ("ref_displacement", float), ("ref_velocity", float),
                                  ("ref_acceleration", float), ("external_force", float)])
    sig["time"] = t
    sig["ref_displacement"] = 0.01 * np.sin(w * t)
    sig["ref_velocity"] = 0.01 * w * np.cos(w * t)
    sig["ref_acceleration"] = -0.01 * w * w * np.sin(w * t)
    return sig


def run(path, start_values=None):
    return simulate_fmu(path, stop_time=2.0, output_interval=1 / 512, input=sine(), output=OUTPUTS,
                        start_values=start_values or {})


def test_fmpy_validation_finds_nothing(fmu3_path):
    assert validate_fmu(fmu3_path) == []
    md = read_model_description(fmu3_path)
    assert md.fmiVersion == "3.0" and md.coSimulation is not None and md.modelExchange is None
    names = {v.name for v in md.modelVariables}
    md2 = read_model_description(os.path.join(os.path.dirname(fmu3_path), "ShakeTable.fmu"))
    # the same inputs, outputs and parameters as the FMI 2.0 FMU (its states are ME only)
    same = {v.name for v in md2.modelVariables if v.causality in ("input", "output", "parameter")}
    assert same <= names and names - same == {"time"}


def test_fmi3_results_are_the_fmi2_results_bit_for_bit(fmu_path, fmu3_path):
    r2, r3 = run(fmu_path), run(fmu3_path)
    for k in OUTPUTS:
        np.testing.assert_array_equal(r3[k], r2[k], err_msg=k)
    # and they are the table's motion: the 10 mm, 2 Hz sine with the loop's gain
    x = r3["displacement"][r3["time"] >= 1.0]
    assert 0.0105 < np.max(np.abs(x)) < 0.0120


def test_start_values_reach_the_binary(fmu_path, fmu3_path):
    heavy = {"table.mass": 2 * 41258.0, "servovalve.model": 2}
    r2, r3 = run(fmu_path, heavy), run(fmu3_path, heavy)
    np.testing.assert_array_equal(r3["acceleration"], r2["acceleration"])
    assert not np.array_equal(r3["acceleration"], run(fmu3_path)["acceleration"])
