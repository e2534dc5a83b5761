#!/usr/bin/env python3
"""Play a drive (`shaketable drive` folder) through ShakeTable.fmu in fmpy, so an FMI user
gets what the tool predicted (issue 19, part 5).

The table's parameters, specimen included, are set as the FMU's start values from a
parameter file (`shaketable fmu start-values`); or the specimen is a separate body in this
master, coupled through `external_force` (`--cosim-specimen MASS_KG,FREQUENCY_HZ,DAMPING`:
an SDOF specimen integrated here by RK4 each communication step, spec section 7). Writes
the achieved table motion and prints its difference from `predicted.csv`.

    python scripts/play_drive.py DRIVE_DIR [--fmu target/fmu/ShakeTable.fmu]
        [--params P.toml] [--cosim-specimen 25000,5,0.02] [--out achieved.csv]
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def start_values(params, binary):
    args = [binary, "fmu", "start-values"] + (["--params", params] if params else [])
    return json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)


def play(fmu, drive, values, specimen=None):
    """Table acceleration, displacement and actuator force for the drive (columns of
    drive.csv), each communication step one sample."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(fmu)
    vr = {sv.name: sv.valueReference for sv in md.modelVariables}
    kinds = {sv.name: sv.type for sv in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="play")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for name, value in values.items():
        if name not in vr:
            continue
        if kinds[name] == "Real":
            slave.setReal([vr[name]], [float(value)])
        elif kinds[name] == "Boolean":
            slave.setBoolean([vr[name]], [bool(value)])
        else:
            slave.setInteger([vr[name]], [int(value)])
    slave.exitInitializationMode()
    t, d, v, a = drive["time_s"], drive["ref_displacement_m"], drive["ref_velocity_m_s"], drive["ref_acceleration_m_s2"]
    h = t[1] - t[0]
    ins = [vr["ref_displacement"], vr["ref_velocity"], vr["ref_acceleration"]]
    outs = [vr["acceleration"], vr["displacement"], vr["actuator_force"], vr["velocity"]]
    n = len(t)
    out = np.zeros((n, 3))
    xs = vs = force_prev = 0.0
    if specimen:
        m, f, z = specimen
        w = 2 * np.pi * f
        ks, cs = m * w * w, 2 * z * m * w
    for k in range(n):
        slave.setReal(ins, [d[k], v[k], a[k]])
        acc, x, force, vel = slave.getReal(outs)
        out[k] = acc, x, force
        if k == n - 1:
            break
        # the inputs ramp linearly to the next sample, as the tool's simulator has them
        slave.setRealInputDerivatives(ins, [1, 1, 1], [(d[k + 1] - d[k]) / h, (v[k + 1] - v[k]) / h, (a[k + 1] - a[k]) / h])
        if specimen:
            # the specimen's force, extrapolated over the step with its last slope
            force_in = ks * (xs - x) + cs * (vs - vel)
            slave.setReal([vr["external_force"]], [force_in])
            slope = (force_in - force_prev) / h if k > 0 else 0.0
            slave.setRealInputDerivatives([vr["external_force"]], [1], [slope])
            force_prev = force_in
        slave.doStep(currentCommunicationPoint=t[k], communicationStepSize=h)
        if specimen:
            x1, v1 = slave.getReal([vr["displacement"], vr["velocity"]])
            # the specimen over the step, with the table's motion linear in the step (RK4)
            def rhs(s, xs_, vs_):
                xt, vt = x + (x1 - x) * s / h, vel + (v1 - vel) * s / h
                return vs_, (-ks * (xs_ - xt) - cs * (vs_ - vt)) / m
            k1 = rhs(0, xs, vs)
            k2 = rhs(h / 2, xs + h / 2 * k1[0], vs + h / 2 * k1[1])
            k3 = rhs(h / 2, xs + h / 2 * k2[0], vs + h / 2 * k2[1])
            k4 = rhs(h, xs + h * k3[0], vs + h * k3[1])
            xs += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            vs += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    slave.terminate()
    slave.freeInstance()
    return out


def read_csv(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("drive_dir")
    ap.add_argument("--fmu", default=os.path.join(ROOT, "target", "fmu", "ShakeTable.fmu"))
    ap.add_argument("--params")
    ap.add_argument("--cosim-specimen", help="MASS_KG,FREQUENCY_HZ,DAMPING_RATIO")
    ap.add_argument("--out")
    ap.add_argument("--binary", default=os.path.join(ROOT, "target", "release", "shaketable"))
    a = ap.parse_args()
    drive = read_csv(os.path.join(a.drive_dir, "drive.csv"))
    specimen = tuple(float(x) for x in a.cosim_specimen.split(",")) if a.cosim_specimen else None
    values = start_values(a.params, a.binary)
    out = play(a.fmu, drive, values, specimen)
    predicted = read_csv(os.path.join(a.drive_dir, "predicted.csv"))
    diff = np.max(np.abs(out[:, 0] - predicted["acceleration_m_s2"]))
    peak = np.max(np.abs(predicted["acceleration_m_s2"]))
    print(f"achieved vs predicted table acceleration: largest difference {diff:.3e} m/s^2 ({100 * diff / peak:.3f} % of the peak)")
    if a.out:
        if os.path.exists(a.out):
            sys.exit(f"{a.out} exists: choose another --out")
        with open(a.out, "w") as f:
            f.write("time_s,acceleration_m_s2,displacement_m,force_n\n")
            for t, row in zip(drive["time_s"], out):
                f.write(f"{t!r},{row[0]!r},{row[1]!r},{row[2]!r}\n")
        print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
