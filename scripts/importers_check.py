#!/usr/bin/env python3
"""ShakeTable.fmu under third-party FMI importers, next to the library's own simulator
(tests/python/test_importers.py).

Runners, all on the same sampled reference `U` (rows k = 0..N at t_k = k h, columns
ref_displacement, ref_velocity, ref_acceleration, external_force):

- `run_libcosim`: OSP libcosim (libcosimpy), an override manipulator setting the inputs
  before every step, a last-value observer reading the outputs after it. libcosim has no
  fmi2SetRealInputDerivatives: the inputs are held over each step (zero-order hold).
- `run_fmpy_hold`: fmpy's `simulate_fmu` (no input derivatives: held as well).
- `run_fmpy_ramp`: fmpy's FMU2Slave driven by hand with the slope of the next interval
  through fmi2SetRealInputDerivatives: the inputs go linearly from U[k] to U[k+1], as
  `shaketable simulate` interpolates its reference. (fmpy's own `set_input_derivatives`
  passes the slope of the interval *ending* at t_k, i.e. extrapolates the last one.)
- `run_simulate`: `shaketable simulate --reference` on the same samples as a
  campaign-format CSV.
- `toolbox_check`, `build_container`: fmu-manipulation-toolbox's checkers and container.

    python scripts/importers_check.py [target/fmu/ShakeTable.fmu]
"""
import argparse
import logging
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
BINARY = os.path.join(ROOT, "target", "release", "shaketable")
INPUTS = ("ref_displacement", "ref_velocity", "ref_acceleration", "external_force")
OUTPUTS = ("displacement", "acceleration", "actuator_force")
# `shaketable simulate`'s column for each FMU output
SIMULATE_COLUMNS = {"displacement": "displacement_m", "acceleration": "acceleration_m_s2",
                    "actuator_force": "force_n"}


def sine_reference(duration_s, step_s, amplitude_m=0.01, frequency_hz=2.0, delay_s=0.0, quantum=None):
    """t_k = k h (k = 0..N) and the analytic sine reference at t_k - delay_s (external force
    zero). With `quantum` every value is rounded to a multiple of it (a power of two): then
    U[k] + ((U[k+1] - U[k]) / h) * h == U[k+1] exactly for a power-of-two h."""
    n = int(round(duration_s / step_s))
    t = np.arange(n + 1) * step_s
    w = 2 * np.pi * frequency_hz
    s = t - delay_s
    u = np.zeros((n + 1, 4))
    u[:, 0] = amplitude_m * np.sin(w * s)
    u[:, 1] = amplitude_m * w * np.cos(w * s)
    u[:, 2] = -amplitude_m * w * w * np.sin(w * s)
    if quantum is not None:
        u = np.round(u / quantum) * quantum
    return t, u


def nrmse(x, ref):
    """RMS of the difference over the RMS of `ref`."""
    x, ref = np.asarray(x), np.asarray(ref)
    return float(np.sqrt(np.mean((x - ref) ** 2)) / np.sqrt(np.mean(ref ** 2)))


def step_ns(step_s):
    """The step in libcosim's integer nanoseconds; refused unless exact (libcosim's clock is
    an int64 count of ns: `CosimExecution.from_step_size` truncates e.g. 1/1024 s =
    976562.5 ns to 976562 ns, a step the FMU would see as 0.000976562 s)."""
    ns = step_s * 1e9
    if ns != round(ns) or round(ns) <= 0 or round(ns) / 1e9 != step_s:
        raise ValueError(f"step {step_s!r} s is not a whole number of nanoseconds "
                         f"({ns!r} ns): libcosim's clock cannot represent it")
    return int(round(ns))


def libcosim_version():
    """(libcosim, libcosimc) versions as 'major.minor.patch' strings."""
    from ctypes import Structure, c_int
    from libcosimpy._internal import libcosimc, wrap_function

    class Version(Structure):
        _fields_ = [("major", c_int), ("minor", c_int), ("patch", c_int)]

    out = []
    for name in ("cosim_libcosim_version", "cosim_libcosimc_version"):
        v = wrap_function(lib=libcosimc(), funcname=name, argtypes=[], restype=Version)()
        out.append(f"{v.major}.{v.minor}.{v.patch}")
    return tuple(out)


def run_libcosim(fmu_path, t, u, outputs=OUTPUTS):
    """Run the FMU in a libcosim execution, inputs u[k] set for the step from t_k.
    Returns (time in ns at t_1..t_N, outputs at t_1..t_N as an (N, len(outputs)) array)."""
    from libcosimpy.CosimEnums import CosimErrorCode
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    h = float(t[1] - t[0])
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_step_size(step_size=step_ns(h))
    slave = CosimLocalSlave(fmu_path=str(fmu_path), instance_name="table")
    index = execution.add_local_slave(local_slave=slave)
    if index < 0:
        raise RuntimeError(f"libcosim could not load {fmu_path}")
    vr = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    inputs = [vr[n] for n in INPUTS]
    outs = [vr[n] for n in outputs]
    manipulator = CosimManipulator.create_override()
    observer = CosimObserver.create_last_value()
    execution.add_manipulator(manipulator=manipulator)
    execution.add_observer(observer=observer)
    times, values = [], []
    for k in range(len(t) - 1):
        if not manipulator.slave_real_values(index, inputs, [float(x) for x in u[k]]):
            raise RuntimeError(f"libcosim refused the inputs of step {k}")
        if not execution.step():
            status = execution.status()
            raise RuntimeError(f"libcosim step {k} failed: {CosimErrorCode(status.error_code)}")
        times.append(execution.status().current_time)
        values.append(observer.last_real_values(index, outs))
    return np.array(times, dtype=np.int64), np.array(values, dtype=float)


def structured_input(t, u):
    sig = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in INPUTS])
    sig["time"] = t
    for j, n in enumerate(INPUTS):
        sig[n] = u[:, j]
    return sig


def run_fmpy_hold(fmu_path, t, u, outputs=OUTPUTS):
    """fmpy's simulate_fmu, inputs held over each step. Returns (time, (N+1, m) outputs)."""
    from fmpy import simulate_fmu
    h = float(t[1] - t[0])
    r = simulate_fmu(str(fmu_path), start_time=0.0, stop_time=float(t[-1]), output_interval=h,
                     input=structured_input(t, u), output=list(outputs))
    return r["time"], np.stack([r[n] for n in outputs], axis=1)


def run_fmpy_ramp(fmu_path, t, u, outputs=OUTPUTS):
    """fmpy's FMU2Slave with fmi2SetRealInputDerivatives = (u[k+1] - u[k]) / h each step:
    the inputs are linear over [t_k, t_k+1]. Returns (N+1, m) outputs at t_0..t_N."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    h = float(t[1] - t[0])
    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    ins = [vr[n] for n in INPUTS]
    outs = [vr[n] for n in outputs]
    unzipped = extract(str(fmu_path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="ramp")
    try:
        slave.instantiate()
        slave.setupExperiment(startTime=float(t[0]))
        slave.enterInitializationMode()
        slave.setReal(ins, [float(x) for x in u[0]])
        slave.exitInitializationMode()
        rows = [slave.getReal(outs)]
        for k in range(len(t) - 1):
            slope = (u[k + 1] - u[k]) / h
            slave.setReal(ins, [float(x) for x in u[k]])
            slave.setRealInputDerivatives(ins, [1] * len(ins), [float(x) for x in slope])
            slave.doStep(currentCommunicationPoint=float(t[k]), communicationStepSize=h)
            rows.append(slave.getReal(outs))
        slave.terminate()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
    return np.array(rows, dtype=float)


def write_reference_csv(path, t, u):
    """Campaign-format reference: time_s and the three ref_* channels (repr: exact)."""
    with open(path, "w") as f:
        f.write("time_s,ref_displacement_m,ref_velocity_m_s,ref_acceleration_m_s2\n")
        for k in range(len(t)):
            f.write(f"{float(t[k])!r},{float(u[k, 0])!r},{float(u[k, 1])!r},{float(u[k, 2])!r}\n")


def run_simulate(t, u, workdir, outputs=OUTPUTS, binary=BINARY):
    """`shaketable simulate` on the reference u (external force must be zero: the campaign
    reference has no force channel). Returns (N+1, m) outputs at t_0..t_N."""
    if np.any(u[:, 3] != 0.0):
        raise ValueError("shaketable simulate takes no external force")
    workdir = Path(workdir)
    ref = workdir / "reference.csv"
    out = workdir / "simulated.csv"
    write_reference_csv(ref, t, u)
    rate = 1.0 / float(t[1] - t[0])
    subprocess.run([binary, "simulate", "--reference", str(ref), "--no-campaign",
                    "--sample-rate", repr(rate), "--out", str(out), "--force"],
                   check=True, capture_output=True, text=True)
    sim = np.genfromtxt(out, delimiter=",", names=True)
    return np.stack([sim[SIMULATE_COLUMNS[n]] for n in outputs], axis=1)


class _Records(logging.Handler):
    def __init__(self):
        super().__init__(level=logging.DEBUG)
        self.records = []

    def emit(self, record):
        self.records.append(record)


def toolbox_check(fmu_path):
    """fmu-manipulation-toolbox's checkers (those of `fmutool -check`: the FMI XSD schema
    and the semantic rules) applied to the FMU. Returns a dict: `errors` and `warnings`
    (messages logged at those levels), `compliant_with` (the FMI version the XSD check
    validated, None when it did not), `semantic_errors`, `checkers` (their names)."""
    from fmu_manipulation_toolbox.checker import (OperationGenericCheck, OperationSemanticCheck,
                                                  get_checkers)
    from fmu_manipulation_toolbox.operations import FMU
    logger = logging.getLogger("fmu_manipulation_toolbox")
    handler = _Records()
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG)
    try:
        checkers = [c() for c in get_checkers()]
        with FMU(str(fmu_path)) as fmu:
            for checker in checkers:
                fmu.apply_operation(checker)
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    generic = [c for c in checkers if isinstance(c, OperationGenericCheck)]
    semantic = [c for c in checkers if isinstance(c, OperationSemanticCheck)]
    return {
        "checkers": [repr(c) for c in checkers],
        "errors": [r.getMessage() for r in handler.records if r.levelno >= logging.ERROR],
        "warnings": [r.getMessage() for r in handler.records if r.levelno == logging.WARNING],
        "compliant_with": generic[0].compliant_with_version if generic else None,
        "semantic_errors": list(semantic[0].errors) if semantic else None,
    }


def build_container(fmu_path, workdir, step_s, name="Container.fmu"):
    """An FMU container (fmu-manipulation-toolbox) holding only the FMU, every input and
    output exposed under its own name, internal step `step_s`. Returns its path."""
    from fmu_manipulation_toolbox.assembly import AssemblyNode
    workdir = Path(workdir)
    shutil.copy(fmu_path, workdir / "ShakeTable.fmu")
    node = AssemblyNode(name, step_size=step_s, auto_input=True, auto_output=True, auto_link=False)
    node.add_fmu("ShakeTable.fmu")
    node.make_fmu(workdir)
    return workdir / name


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("fmu", nargs="?", default=os.path.join(ROOT, "target", "fmu", "ShakeTable.fmu"))
    a = ap.parse_args()
    t, u = sine_reference(2.0, 1 / 512)
    ns, co = run_libcosim(a.fmu, t, u)
    _, fm = run_fmpy_hold(a.fmu, t, u)
    print("libcosim", *libcosim_version(), "vs fmpy (held inputs): bit-identical =",
          np.array_equal(co, fm[1:]))
    with tempfile.TemporaryDirectory() as d:
        _, ud = sine_reference(2.0, 1 / 512, delay_s=1 / 1024)
        sim = run_simulate(t, ud, d)
    for j, n in enumerate(OUTPUTS):
        print(f"{n}: NRMSE libcosim vs simulate (reference delayed h/2) = {nrmse(co[:, j], sim[1:, j]):.2e}")
    print("toolbox check:", toolbox_check(a.fmu))


if __name__ == "__main__":
    main()
