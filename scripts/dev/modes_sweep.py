#!/usr/bin/env python3
"""Diagnosis of specimens of one to three modes over seeds, noise levels and tables
(issue 17 part 1), for development: not a test, its draws are not checked for visibility.

For every (table, noise scale, modes, seed): draw a specimen scaled to the table, `shaketable
campaign synth` a campaign with 30-s random tests, `shaketable diagnose --json` it and print
the causes, the fitted against the true mode frequencies and masses, the gain and the time:

    scripts/dev/modes_sweep.py --seeds 1-4 --modes 2,3 --noise 1,3 \
        --table 41t --table 6t=scripts/dev/table_6t.toml

Draws: mode 1 at 2-8 Hz with 0.2-0.8 of the table's mass; each further mode at 2.5-3.5
times the previous one's frequency (below 40 Hz, where the mass test's apparent mass is
read) with 30-70 % of its mass; damping 1-4 %. Noise scale 1 is `campaign synth`'s default.
"""
import argparse
import json
import os
import random
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
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BIN = os.path.join(ROOT, "target", "release", "shaketable")
HIGHEST_MODE_HZ = 40.0


def seeds(text):
    lo, _, hi = text.partition("-")
    return range(int(lo), int(hi or lo) + 1)


def draw(rng, table_kg, n):
    while True:
        modes = []
        f = rng.uniform(2.0, 8.0)
        m = rng.uniform(0.2, 0.8) * table_kg
        for k in range(n):
            if k > 0:
                f *= rng.uniform(2.5, 3.5)
                m *= rng.uniform(0.3, 0.7)
            modes.append((m, f, rng.uniform(0.01, 0.04)))
        if f < HIGHEST_MODE_HZ:
            break
    keys = []
    for k, (m, f, z) in enumerate(modes):
        p = "" if k == 0 else f"mode{k + 1}."
        keys += [f"{p}mass_kg={m:.1f}", f"{p}frequency_hz={f:.4f}", f"{p}damping_ratio={z:.4f}"]
    return "specimen:" + ",".join(keys), modes


def fitted_modes(cause):
    p = cause["parameters"]
    modes = p.get("modes") or [p]
    return [(m["mass_kg"], m["frequency_hz"]) for m in modes]


def run(table, params, noise, n, seed):
    with open(params, "rb") if params else open(os.devnull, "rb") as f:
        mass = tomllib.load(f)["table"]["mass_kg"] if params else 41258.0
    spec, modes = draw(random.Random(seed * 31 + n), mass, n)
    with tempfile.TemporaryDirectory() as tmp:
        camp = os.path.join(tmp, "c")
        args = [BIN, "campaign", "synth", "--quiet", "--random-duration", "30",
                "--seed", str(seed), "--effect", spec, camp]
        if params:
            args += ["--params", params]
        for k, v in DEFAULT_NOISE.items():
            args += [f"--noise-{k}", str(v * noise)]
        subprocess.run(args, check=True)
        out = os.path.join(tmp, "d.json")
        t0 = time.time()
        subprocess.run([BIN, "diagnose", "--quiet", camp, "--json", out], check=True,
                       stdout=subprocess.DEVNULL)
        dt = time.time() - t0
        with open(out) as f:
            d = json.load(f)
    names = [c["effect"] for c in d["causes"]]
    spec_cause = next((c for c in d["causes"] if c["effect"] == "specimen"), None)
    got = fitted_modes(spec_cause) if spec_cause else []
    ok = names == ["specimen"] and len(got) == n and all(
        abs(g[1] / t[1] - 1) < 0.05 for g, t in zip(got, modes))
    true_txt = " ".join(f"{f:.2f}Hz/{m / 1e3:.1f}t" for m, f, _ in modes)
    got_txt = " ".join(f"{f:.2f}Hz/{m / 1e3:.1f}t" for m, f in got)
    print(f"{'ok ' if ok else 'BAD'} {table:4} noise {noise:g} modes {n} seed {seed:3}: "
          f"true {true_txt} | fitted {got_txt} | causes {names} gain {d['gain']:.2f} "
          f"explained {d['explained']} ({dt:.0f} s)", flush=True)
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=seeds, default=seeds("1-3"))
    ap.add_argument("--modes", default="2,3")
    ap.add_argument("--noise", default="1")
    ap.add_argument("--table", action="append", default=None,
                    help="NAME or NAME=params.toml (41t: the defaults)")
    a = ap.parse_args()
    tables = [t.partition("=") for t in (a.table or ["41t"])]
    bad = 0
    for name, _, params in tables:
        for noise in map(float, a.noise.split(",")):
            for n in map(int, a.modes.split(",")):
                for seed in a.seeds:
                    bad += not run(name, params or None, noise, n, seed)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
