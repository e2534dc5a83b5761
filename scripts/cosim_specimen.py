#!/usr/bin/env python3
"""Co-simulation: the table FMU coupled through force with a flexible specimen model
integrated in this Python master (fmpy), checked against the model's own `specimen`.

Specimen: m_s x_s'' = -k_s (x_s - x) - c_s (x_s' - x'), 10 t, 5 Hz, 2 % damping
(spec section 7). Each communication step (default 1/1024 s) the master reads the table's
displacement and velocity, sets `external_force` = k_s (x_s - x) + c_s (x_s' - x') with its
slope (first-order extrapolation through fmi2SetRealInputDerivatives), steps the table,
then integrates the specimen over the same step (RK4, table motion linear in the step).
The same reference drives the FMU with `specimen.enabled` for comparison: table TF peak
frequencies and RMS of the table acceleration must agree within 2 %.

    python scripts/cosim_specimen.py [target/fmu/ShakeTable.fmu] [--step 0.0009765625]
"""
import argparse
import os
import sys

import numpy as np
from scipy import signal

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fmu_frf import random_reference  # noqa: E402

MASS, FREQ, ZETA = 10000.0, 5.0, 0.02


def fmu_slave(fmu, name):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(fmu)
    vr = {sv.name: sv.valueReference for sv in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    return slave, vr


def run(fmu, t, d, v, a, coupled):
    """Table acceleration for the reference; `coupled`: specimen in this master, else the
    FMU's own specimen effect."""
    slave, vr = fmu_slave(fmu, "cosim" if coupled else "internal")
    if not coupled:
        slave.setBoolean([vr["specimen.enabled"]], [True])
        slave.setReal([vr["specimen.mass"], vr["specimen.frequency"], vr["specimen.damping_ratio"]], [MASS, FREQ, ZETA])
    slave.exitInitializationMode()
    ins = [vr["ref_displacement"], vr["ref_velocity"], vr["ref_acceleration"]]
    outs = [vr["displacement"], vr["velocity"], vr["acceleration"]]
    fe = vr["external_force"]
    w = 2 * np.pi * FREQ
    ks, cs = MASS * w * w, 2 * ZETA * MASS * w
    xs = vs = 0.0
    h = t[1] - t[0]
    u = np.stack([d, v, a], axis=1)
    acc = np.zeros(len(t))
    x0, v0, acc[0] = slave.getReal(outs)
    f_prev = 0.0
    for k in range(len(t) - 1):
        slave.setReal(ins, list(u[k]))
        slave.setRealInputDerivatives(ins, [1, 1, 1], list((u[k + 1] - u[k]) / h))
        if coupled:
            f = ks * (xs - x0) + cs * (vs - v0)
            slave.setReal([fe], [f])
            slave.setRealInputDerivatives([fe], [1], [(f - f_prev) / h if k > 0 else 0.0])
            f_prev = f
        slave.doStep(t[k], h)
        x1, v1, acc[k + 1] = slave.getReal(outs)
        if coupled:
            # RK4 of the specimen on the table motion, linear over the step
            def rhs(s, y, yd):
                tx = x0 + s * (x1 - x0)
                tv = v0 + s * (v1 - v0)
                return yd, (-ks * (y - tx) - cs * (yd - tv)) / MASS
            k1 = rhs(0.0, xs, vs)
            k2 = rhs(0.5, xs + 0.5 * h * k1[0], vs + 0.5 * h * k1[1])
            k3 = rhs(0.5, xs + 0.5 * h * k2[0], vs + 0.5 * h * k2[1])
            k4 = rhs(1.0, xs + h * k3[0], vs + h * k3[1])
            xs += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            vs += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        x0, v0 = x1, v1
    slave.terminate()
    slave.freeInstance()
    return acc


def compare(fmu, step=1.0 / 1024, duration=64.0, seed=3):
    t512, d, v, a = random_reference(rms=0.4905, band=(0.5, 30.0), duration=duration, seed=seed)
    # the same continuous reference at the communication step (linear interpolation)
    t = np.arange(0, t512[-1] + 1e-12, step)
    d, v, a = (np.interp(t, t512, s) for s in (d, v, a))
    res = {}
    fs = 1.0 / step
    skip = int(2 * fs)
    nper = int(round(4 * fs))
    for coupled in (True, False):
        acc = run(fmu, t, d, v, a, coupled)
        f, pxy = signal.csd(a[skip:], acc[skip:], fs=fs, nperseg=nper)
        _, pxx = signal.welch(a[skip:], fs=fs, nperseg=nper)
        hh = pxy / pxx
        mag = np.abs(hh)
        # the specimen's resonance/anti-resonance pair and the oil-column peak
        below = (f >= FREQ - 1.5) & (f <= FREQ)
        above = (f >= FREQ) & (f <= FREQ + 1.5)
        res[coupled] = {
            "rms_acceleration": float(np.sqrt(np.mean(acc[skip:] ** 2))),
            "peak_hz": float(f[(f >= 8) & (f <= 25)][np.argmax(mag[(f >= 8) & (f <= 25)])]),
            "notch_hz": float(f[above][np.argmin(mag[above])]),
            "resonance_hz": float(f[below][np.argmax(mag[below])]),
        }
    return res[True], res[False]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmu", nargs="?", default="target/fmu/ShakeTable.fmu")
    p.add_argument("--step", type=float, default=1.0 / 1024)
    p.add_argument("--duration", type=float, default=64.0)
    args = p.parse_args(argv)
    co, internal = compare(args.fmu, args.step, args.duration)
    print(f"table FMU + {MASS/1000:.0f} t, {FREQ} Hz, {100*ZETA:.0f} % specimen at a {args.step:.6g} s communication step")
    print(f"  {'':24} {'co-simulated':>14} {'FMU specimen':>14} {'difference':>11}")
    worst = 0.0
    for k in ("rms_acceleration", "peak_hz", "resonance_hz", "notch_hz"):
        diff = co[k] / internal[k] - 1
        worst = max(worst, abs(diff))
        print(f"  {k:24} {co[k]:14.4f} {internal[k]:14.4f} {100*diff:+10.2f} %")
    print(f"  largest difference {100*worst:.2f} % ({'within' if worst <= 0.02 else 'OUTSIDE'} 2 %)")
    return co, internal


if __name__ == "__main__":
    main()
