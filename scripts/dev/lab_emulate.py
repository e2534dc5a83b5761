#!/usr/bin/env python3
"""A laboratory's recordings emulated from a synthetic campaign (issue 16, held-out check).

`shaketable campaign synth` writes the paper program with every channel at 512 Hz. A
laboratory brings less: no valve command, spool or force; its own sample rate, column
names, units and header block; no gains and no geometry. This script makes such a
campaign from a synthetic one, then runs `identify` and `diagnose` on it as a new user
would and prints what they said against the truth:

    scripts/dev/lab_emulate.py --seed 5 --rate 1000 \
        --effect specimen:mass_kg=30000,frequency_hz=4,damping_ratio=0.03 OUT_DIR

The campaign is synthesised at `--rate` (`campaign synth --sample-rate`), each recording
written as tab-separated text in mm, g and volts of reference (10 mm/V) after a
four-line header block, and mapped back by campaign.toml's `[columns]`. The campaign gives
no gains or geometry; a test's own controller override (the paper's R1 runs without the
feed-forward) is kept, as a lab that knows its programme writes it, unless
`--no-test-gains`.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
BIN = os.path.join(HERE, "..", "..", "target", "release", "shaketable")
MM_PER_V = 10.0
G = 9.80665


def run(args):
    t0 = time.time()
    out = subprocess.run([BIN, *args], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"shaketable {' '.join(args)} failed:\n{out.stderr}")
    return time.time() - t0


def lab_file(src, dst, control, channels, ref_both):
    with open(src) as f:
        rows = list(csv.DictReader(f))
    cols = {k: [float(r[k]) for r in rows] for k in rows[0]}
    ref = "ref_displacement_m" if control == "displacement" else "ref_acceleration_m_s2"
    out = {}
    volts = 1000.0 / MM_PER_V if ref.endswith("_m") else 1.0 / G
    out["REF"] = [v * volts for v in cols[ref]]
    if ref_both and control == "acceleration":
        out["REF_D"] = [v * 1000.0 / MM_PER_V for v in cols["ref_displacement_m"]]
    if "displacement" in channels:
        out["LVDT_mm"] = [v * 1000.0 for v in cols["displacement_m"]]
    if "acceleration" in channels:
        out["ACC_g"] = [v / G for v in cols["acceleration_m_s2"]]
    n = min(len(v) for v in out.values())
    with open(dst, "w") as f:
        f.write("Emulated DAQ export\nOperator: dev\nDate: 2026-11-27\n")
        f.write("\t".join(["Sample", *out.keys()]) + "\n")
        for k in range(n):
            f.write("\t".join([str(k + 1), *(f"{out[c][k]:.7g}" for c in out)]) + "\n")


def lab_campaign(synth_dir, out_dir, rate_hz, channels, ref_both, test_gains=True):
    with open(os.path.join(synth_dir, "campaign.toml"), "rb") as f:
        camp = tomllib.load(f)
    os.makedirs(out_dir, exist_ok=True)
    lines = [
        'name = "emulated laboratory recordings"',
        f"sample_rate_hz = {rate_hz}",
        "",
        "[read]",
        'delimiter = "\\t"',
        "header_line = 4",
        "",
        "[columns]",
    ]
    if "displacement" in channels:
        lines.append('displacement_m = { column = "LVDT_mm", scale = 0.001 }')
    if "acceleration" in channels:
        lines.append(f'acceleration_m_s2 = {{ column = "ACC_g", scale = {G} }}')
    for t in camp["test"]:
        name = f"{t['kind']}-{t['name'].lower()}"
        lab_file(
            os.path.join(synth_dir, t["file"]),
            os.path.join(out_dir, name + ".txt"),
            t["control"],
            channels,
            ref_both,
        )
        lines += ["", "[[test]]", f'name = "{name}"', f'file = "{name}.txt"']
        lines += [f'kind = "{t["kind"]}"', f'control = "{t["control"]}"']
        for key in ("frequency_hz", "amplitude_m", "rms", "band_hz"):
            if key in t:
                lines.append(f"{key} = {t[key]}")
        if "controller" in t and test_gains:
            gains = ", ".join(f"{k} = {v}" for k, v in t["controller"].items())
            lines.append(f"controller = {{ {gains} }}")
        # each test maps its own reference: the controlled quantity differs by test
        if t["control"] == "acceleration":
            ref = f'ref_acceleration_m_s2 = {{ column = "REF", scale = {G} }}'
            if ref_both:
                ref += f', ref_displacement_m = {{ column = "REF_D", scale = {MM_PER_V / 1000.0} }}'
        else:
            ref = f'ref_displacement_m = {{ column = "REF", scale = {MM_PER_V / 1000.0} }}'
        lines.append(f"columns = {{ {ref} }}")
    with open(os.path.join(out_dir, "campaign.toml"), "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--rate", type=float, default=1000.0)
    ap.add_argument("--effect", action="append", default=[])
    ap.add_argument("--params")
    ap.add_argument("--channels", default="displacement,acceleration")
    ap.add_argument("--random-duration", default="30")
    ap.add_argument("--identify-only", action="store_true")
    ap.add_argument("--ref-both", action="store_true",
                    help="acceleration-controlled tests record their displacement reference too")
    ap.add_argument("--no-test-gains", action="store_true",
                    help="drop the tests' own controller overrides (R1's fv = 0): a lab that "
                         "does not say which tests ran another controller (a known limit)")
    args = ap.parse_args()
    synth = args.out_dir + ".synth"
    cmd = ["campaign", "synth", "--quiet", "--force", "--seed", str(args.seed)]
    cmd += ["--sample-rate", str(args.rate)]
    cmd += ["--random-duration", args.random_duration]
    if args.params:
        cmd += ["--params", args.params]
    for e in args.effect:
        cmd += ["--effect", e]
    run(cmd + [synth])
    lab_campaign(synth, args.out_dir, args.rate, args.channels.split(","), args.ref_both,
                 not args.no_test_gains)
    run(["campaign", "check", args.out_dir])
    j_id = os.path.join(args.out_dir, "..", os.path.basename(args.out_dir) + ".id.json")
    t_id = run(["identify", args.out_dir, "--json", j_id, "--force"])
    with open(j_id) as f:
        ident = json.load(f)
    print(f"identify {t_id:.1f} s; closed-loop fit %, estimation | validation tests:")
    for role in ("estimation", "validation"):
        for chan in ("displacement_m", "acceleration_m_s2"):
            fits = [x["fit_percent"] for x in ident["closed_loop"]["fits"]
                    if x["role"] == role and x["channel"] == chan]
            if fits:
                print(f"  {role:10} {chan:18} min {min(fits):6.1f}  median {sorted(fits)[len(fits) // 2]:6.1f}")
    for c in ident["closed_loop"]["combinations"]:
        print(f"  {c['name']:26} {c['value']:.4g} +- {c['sigma']}")
    if args.identify_only:
        return
    j_d = os.path.join(args.out_dir, "..", os.path.basename(args.out_dir) + ".diag.json")
    t_d = run(["diagnose", "--quiet", args.out_dir, "--json", j_d, "--force"])
    with open(j_d) as f:
        d = json.load(f)
    print(f"identify {t_id:.1f} s, diagnose {t_d:.1f} s")
    print("truth effects:", args.effect or "none")
    print("baseline_from:", d.get("baseline_from"), " cause:", d.get("cause"))
    for c in d.get("causes", []):
        print("  cause", c["effect"], json.dumps(c["parameters"]), "gain", c["gain"])
    print("explained:", d.get("explained"), " gain:", d.get("gain"))
    for p in d.get("partial", []):
        print("  partial:", json.dumps(p)[:200])
    for n in d.get("not_testable", []):
        print("  not testable:", json.dumps(n)[:200])


if __name__ == "__main__":
    main()
