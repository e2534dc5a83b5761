#!/usr/bin/env python3
"""Measure the table transfer function through the FMU, as a lab would.

A random reference in acceleration control (0.1 g RMS, 0.5-50 Hz, 64 s at 512 Hz, with
exact spectral derivatives for velocity and displacement) drives the FMU through fmpy;
Welch/CSD (scipy) from ref_acceleration to acceleration gives the table TF, whose peak,
low-frequency gain and phase inversion are printed, plotted and written as JSON.

    python scripts/fmu_frf.py target/fmu/ShakeTable.fmu [--out DIR] [--set table.mass=82516]
"""
import argparse
import json
import os
import sys

import numpy as np
from scipy import signal

FS = 512.0


def random_reference(rms=0.981, band=(0.5, 50.0), duration=64.0, fade=1.0, seed=1):
    """Band-limited random acceleration with consistent velocity and displacement.

    The periodic band-limited signal is built in the frequency domain (flat amplitude,
    random phases); velocity and displacement are its exact spectral integrals. A raised
    cosine fade w(t) at both ends starts and ends the table at rest; the derivatives of the
    product are taken analytically (d = w x, v = w' x + w x', a = w'' x + 2 w' x' + w x'')."""
    n = int(round(duration * FS))
    f = np.fft.rfftfreq(n, 1 / FS)
    rng = np.random.default_rng(seed)
    spec = np.zeros(len(f), complex)
    band_bins = (f >= band[0]) & (f <= band[1])
    spec[band_bins] = np.exp(2j * np.pi * rng.random(band_bins.sum()))
    jw = 2j * np.pi * f
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.fft.irfft(np.where(band_bins, spec / jw**2, 0), n)
        xd = np.fft.irfft(np.where(band_bins, spec / jw, 0), n)
    xdd = np.fft.irfft(spec, n)
    t = np.arange(n) / FS
    nf = int(fade * FS)
    w = np.ones(n)
    wd = np.zeros(n)
    wdd = np.zeros(n)
    c = np.pi / fade
    for sl, tt in ((slice(0, nf), t[:nf]), (slice(n - nf, n), duration - t[n - nf:])):
        sign = 1.0 if sl.start == 0 else -1.0
        w[sl] = 0.5 * (1 - np.cos(c * tt))
        wd[sl] = sign * 0.5 * c * np.sin(c * tt)
        wdd[sl] = 0.5 * c * c * np.cos(c * tt)
    a = w * xdd
    scale = rms / np.sqrt(np.mean(a[nf:n - nf] ** 2))
    x, xd, xdd = x * scale, xd * scale, xdd * scale
    return t, w * x, wd * x + w * xd, wdd * x + 2 * wd * xd + w * xdd


def run_fmu(fmu, t, d, v, a, params=None, outputs=("acceleration",), external=None, name="frf"):
    """Drive the FMU at the reference's sample rate with linear input interpolation."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(fmu)
    vr = {sv.name: sv.valueReference for sv in md.modelVariables}
    types = {sv.name: sv.type for sv in md.modelVariables}
    unzipdir = extract(fmu)
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for k, val in (params or {}).items():
        if types[k] == "Real":
            slave.setReal([vr[k]], [float(val)])
        elif types[k] in ("Integer", "Enumeration"):
            slave.setInteger([vr[k]], [int(val)])
        else:
            slave.setBoolean([vr[k]], [bool(val)])
    slave.exitInitializationMode()
    ins = [vr["ref_displacement"], vr["ref_velocity"], vr["ref_acceleration"]]
    outs = [vr[o] for o in outputs]
    h = t[1] - t[0]
    res = np.zeros((len(t), len(outs)))
    res[0] = slave.getReal(outs)
    u = np.stack([d, v, a], axis=1)
    for k in range(len(t) - 1):
        slave.setReal(ins, list(u[k]))
        slave.setRealInputDerivatives(ins, [1, 1, 1], list((u[k + 1] - u[k]) / h))
        slave.doStep(t[k], h)
        res[k + 1] = slave.getReal(outs)
    slave.terminate()
    slave.freeInstance()
    return res


def tf_figures(f, h):
    """Peak (parabolic refinement), low-frequency gain, phase drop over +-1 Hz, steepest."""
    mag = np.abs(h)
    sel = (f >= 2) & (f <= 40)
    i = np.flatnonzero(sel)[np.argmax(mag[sel])]
    y0, y1, y2 = mag[i - 1], mag[i], mag[i + 1]
    den = y0 - 2 * y1 + y2
    dlt = 0.5 * (y0 - y2) / den if den != 0 else 0.0
    df = f[1] - f[0]
    peak = f[i] + dlt * df
    gain = y1 - 0.25 * (y0 - y2) * dlt
    low = float(np.mean(mag[(f >= 0.75) & (f <= 1.5)]))
    ph = np.unwrap(np.angle(h))
    drop = np.degrees(np.interp(peak - 1, f, ph) - np.interp(peak + 1, f, ph))
    mid = 0.5 * (f[1:] + f[:-1])
    slope = -np.diff(ph) / df
    near = np.abs(mid - peak) <= 1.0
    steep = mid[near][np.argmax(slope[near])]
    return {"peak_hz": float(peak), "peak_gain": float(gain), "low_frequency_gain": low,
            "peak_ratio": float(gain / low), "phase_drop_deg": float(drop), "steepest_hz": float(steep)}


def measure(fmu, params=None, duration=64.0, seed=1):
    t, d, v, a = random_reference(duration=duration, seed=seed)
    acc = run_fmu(fmu, t, d, v, a, params)[:, 0]
    skip = int(2 * FS)
    f, pxy = signal.csd(a[skip:], acc[skip:], fs=FS, nperseg=2048)
    _, pxx = signal.welch(a[skip:], fs=FS, nperseg=2048)
    h = pxy / pxx
    return f, h, tf_figures(f, h)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmu")
    p.add_argument("--out", default=None, help="directory for frf_fmu.png and figures_fmu.json")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="FMU parameter, e.g. table.mass=82516")
    p.add_argument("--duration", type=float, default=64.0)
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args(argv)
    params = {}
    for s in args.set:
        k, _, val = s.partition("=")
        params[k.strip()] = float(val)
    f, h, fig = measure(args.fmu, params, args.duration, args.seed)
    print("table TF through the FMU (fmpy; random 0.1 g, 0.5-50 Hz; Welch/CSD, Hann, 2048 samples):")
    print(f"  peak frequency       {fig['peak_hz']:8.3f} Hz")
    print(f"  peak gain            {fig['peak_gain']:8.3f}  ({fig['peak_ratio']:.2f} x the low-frequency gain)")
    print(f"  low-frequency gain   {fig['low_frequency_gain']:8.4f}  (mean over 0.75-1.5 Hz)")
    print(f"  phase drop +-1 Hz    {fig['phase_drop_deg']:8.1f} deg")
    print(f"  steepest phase       {fig['steepest_hz']:8.3f} Hz")
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "figures_fmu.json"), "w") as fh:
            json.dump(fig, fh, indent=2)
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        sel = (f >= 0.5) & (f <= 50)
        fig_, ax = plt.subplots(2, 1, sharex=True, figsize=(9, 7))
        ax[0].semilogx(f[sel], np.abs(h[sel]))
        ax[0].set_ylabel("|H| (-)")
        ax[0].set_title(f"Table TF through the FMU, peak {fig['peak_hz']:.2f} Hz")
        ax[1].semilogx(f[sel], np.degrees(np.unwrap(np.angle(h[sel]))))
        ax[1].set_ylabel("phase (deg)")
        ax[1].set_xlabel("frequency (Hz)")
        for a_ in ax:
            a_.grid(True, which="both", alpha=0.3)
        fig_.savefig(os.path.join(args.out, "frf_fmu.png"), dpi=100)
        print(f"wrote {os.path.join(args.out, 'frf_fmu.png')}, {os.path.join(args.out, 'figures_fmu.json')}")
    return fig


if __name__ == "__main__":
    main()
    sys.exit(0)
