"""Shared fixtures: the built FMU (scripts/build_fmu.sh is run when it is missing)."""
import os
import subprocess
import sys

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))


@pytest.fixture(scope="session")
def fmu_path():
    path = os.path.join(ROOT, "target", "fmu", "ShakeTable.fmu")
    if not os.path.exists(path):
        subprocess.run(["bash", os.path.join(ROOT, "scripts", "build_fmu.sh")], check=True)
    return path
