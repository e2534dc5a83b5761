"""The FMU's binary loads on old Linux machines: it needs no glibc symbol newer than
2.17 (manylinux2014's baseline: RHEL 7, Ubuntu 18.04, Debian 9 and later) and exports the
FMI functions only (issue 18, part 1): the FMI 2.0 ones and, for ShakeTable3.fmu, the
FMI 3.0 ones (one binary serves both FMUs)."""
import re
import subprocess
import zipfile

BASELINE = (2, 17)


def shipped_binary(fmu_path, tmp_path):
    with zipfile.ZipFile(fmu_path) as z:
        return z.extract("binaries/linux64/ShakeTable.so", tmp_path)


def test_no_glibc_symbol_newer_than_2_17(fmu_path, tmp_path):
    so = shipped_binary(fmu_path, tmp_path)
    out = subprocess.run(["readelf", "-V", "-W", so], check=True, capture_output=True, text=True).stdout
    versions = {tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBC_([0-9.]+[0-9])", out)}
    assert versions, "no GLIBC version needs found: not a glibc-linked binary?"
    newer = sorted(v for v in versions if v > BASELINE)
    assert not newer, f"needs glibc {newer}, newer than {BASELINE}"


def test_exports_fmi_functions_only(fmu_path, tmp_path):
    so = shipped_binary(fmu_path, tmp_path)
    out = subprocess.run(["nm", "-D", "--defined-only", so], check=True, capture_output=True, text=True).stdout
    names = [line.split()[-1] for line in out.splitlines() if line.strip()]
    stray = [n for n in names if not n.startswith(("fmi2", "fmi3"))]
    assert not stray, f"exported besides fmi2* and fmi3*: {stray[:10]}"
    assert "fmi2DoStep" in names and "fmi2Instantiate" in names
    assert "fmi3DoStep" in names and "fmi3InstantiateCoSimulation" in names
    # the FMI 3.0 FMU ships the very same binary
    with zipfile.ZipFile(fmu_path.replace("ShakeTable.fmu", "ShakeTable3.fmu")) as z:
        assert z.read("binaries/x86_64-linux/ShakeTable.so") == open(so, "rb").read()
