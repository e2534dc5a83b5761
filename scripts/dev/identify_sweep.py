#!/usr/bin/env python3
"""Identification accuracy over seeds, noise levels and tables (issue 17 part 6).

For every (table, noise scale, seed): `shaketable campaign synth` a campaign, `shaketable
identify --json` it and compare with its truth.toml. Prints one row per run and, per
(table, noise), the mean and spread of the relative errors, in percent:

    scripts/dev/identify_sweep.py --seeds 1-6 --noise 1,3 \
        --table 41t --table 6t=scripts/dev/table_6t.toml [--csv out.csv]

Noise scale 1 is `campaign synth`'s default sensor noise (spool 0.002, displacement
2e-5 m, acceleration 0.01 m/s^2, force 200 N, RMS), 3 three times each. The oil-column
truth follows spec section 4: f = sqrt(4 beta A^2 / (V M)) / (2 pi),
zeta = (C_l / A) sqrt(beta M / V).
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import time
import tomllib

DEFAULT_NOISE = {
    "spool": 0.002,
    "displacement": 2e-5,
    "acceleration": 0.01,
    "force": 200.0,
}
COLUMNS = ["f_oil", "zeta_oil", "beta", "mass", "F_mu", "Y", "b", "peak_hz"]


def seeds_of(text):
    out = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            out.extend(range(int(a), int(b) + 1))
        else:
            out.append(int(part))
    return out


def oil_truth(t):
    a = t["actuator"]
    m = t["table"]["mass_kg"]
    beta, area, vol = a["bulk_modulus_pa"], a["piston_area_m2"], a["total_oil_volume_m3"]
    f = math.sqrt(4 * beta * area**2 / (vol * m)) / (2 * math.pi)
    zeta = a["leakage_m3_s_pa"] / area * math.sqrt(beta * m / vol)
    return f, zeta, beta


def rel(est, true):
    if est is None or true in (None, 0):
        return float("nan")
    return 100.0 * (est / true - 1.0)


def run_one(exe, workdir, params, seed, scale):
    out = os.path.join(workdir, f"c{seed}")
    cmd = [exe, "campaign", "synth", out, "--seed", str(seed), "--quiet", "--force"]
    if params:
        cmd += ["--params", params]
    for k, v in DEFAULT_NOISE.items():
        cmd += [f"--noise-{k}", repr(v * scale)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    js = os.path.join(workdir, f"c{seed}.json")
    t0 = time.time()
    subprocess.run(
        [exe, "identify", out, "--json", js, "--force"], check=True, stdout=subprocess.DEVNULL
    )
    secs = time.time() - t0
    with open(js) as f:
        j = json.load(f)
    with open(os.path.join(out, "truth.toml"), "rb") as f:
        t = tomllib.load(f)
    f_true, z_true, b_true = oil_truth(t)
    oil = j.get("oil_column", {})
    fr = j.get("friction", {})
    val = j.get("validation", {})
    row = {
        "f_oil": rel(oil.get("frequency_hz"), f_true),
        "zeta_oil": rel(oil.get("damping_ratio"), z_true),
        "beta": rel(oil.get("bulk_modulus_pa"), b_true),
        "mass": rel(j.get("table", {}).get("mass_kg"), t["table"]["mass_kg"]),
        "F_mu": rel(fr.get("force_n"), t["friction"]["force_n"]),
        "Y": rel(fr.get("yield_displacement_m"), t["friction"]["yield_displacement_m"]),
        "b": rel(fr.get("shape"), t["friction"]["shape"]),
        "peak_hz": rel(val.get("peak_hz"), val.get("measured_peak_hz")),
        "actuator": j.get("actuator", {}).get("model"),
        "identify_s": secs,
    }
    return row


def stats(values):
    v = [x for x in values if not math.isnan(x)]
    if not v:
        return float("nan"), float("nan")
    mean = sum(v) / len(v)
    sd = math.sqrt(sum((x - mean) ** 2 for x in v) / max(len(v) - 1, 1))
    return mean, sd


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--exe", default="target/release/shaketable")
    ap.add_argument("--seeds", default="1-6")
    ap.add_argument("--noise", default="1,3", help="noise scales, comma separated")
    ap.add_argument(
        "--table",
        action="append",
        help="NAME or NAME=PARAMS.toml (repeatable; default: 41t, the TREES Lab defaults)",
    )
    ap.add_argument("--csv", help="write every run here")
    args = ap.parse_args()
    tables = []
    for spec in args.table or ["41t"]:
        name, _, params = spec.partition("=")
        tables.append((name, os.path.abspath(params) if params else None))
    exe = os.path.abspath(args.exe)
    rows = []
    with tempfile.TemporaryDirectory(prefix="identify_sweep") as work:
        for name, params in tables:
            for scale in [float(s) for s in args.noise.split(",")]:
                for seed in seeds_of(args.seeds):
                    r = run_one(exe, work, params, seed, scale)
                    r.update(table=name, noise=scale, seed=seed)
                    rows.append(r)
                    cells = " ".join(f"{r[c]:+7.2f}" for c in COLUMNS)
                    print(f"{name:>5} x{scale:<4g} seed {seed:<3} {cells}  {r['actuator']}", flush=True)
    print()
    print("| table | noise | runs | " + " | ".join(f"{c} % mean (sd)" for c in COLUMNS) + " | nonlinear |")
    print("|---|---|---|" + "---|" * (len(COLUMNS) + 1))
    groups = {}
    for r in rows:
        groups.setdefault((r["table"], r["noise"]), []).append(r)
    for (name, scale), g in groups.items():
        cells = []
        for c in COLUMNS:
            m, s = stats([r[c] for r in g])
            cells.append(f"{m:+.2f} ({s:.2f})")
        nl = sum(r["actuator"] == "nonlinear" for r in g)
        print(f"| {name} | x{scale:g} | {len(g)} | " + " | ".join(cells) + f" | {nl}/{len(g)} |")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=["table", "noise", "seed"] + COLUMNS + ["actuator", "identify_s"])
            w.writeheader()
            for r in rows:
                w.writerow({k: r[k] for k in w.fieldnames})
    return 0


if __name__ == "__main__":
    sys.exit(main())
