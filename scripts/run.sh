#!/usr/bin/env bash
# README command 1: set up, build in release and run the main job on the built-in
# TREES Lab defaults. Everything it writes goes to report/.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
source scripts/setup.sh

echo "== build (release)"
cargo build --release --locked
BIN="$ROOT/target/release/shaketable"
mkdir -p report

echo
echo "== 1. TREES Lab table: analytic closed-loop frequency response (spec section 6)"
"$BIN" params --defaults > report/trees_lab.toml
"$BIN" frf --params report/trees_lab.toml --out report/frf

if [ -x scripts/build_fmu.sh ]; then
  echo
  echo "== 2. The table as an FMI 2.0 Co-Simulation FMU, measured through fmpy"
  scripts/build_fmu.sh
  "$ROOT/.venv/bin/python" scripts/fmu_frf.py target/fmu/ShakeTable.fmu --out report/fmu
fi

echo
echo "== 3. Identification (paper section 4) of the paper's campaign synthesised from the defaults"
"$BIN" campaign synth --quiet --force --seed 1 report/campaign
mkdir -p report/identification
"$BIN" identify report/campaign --json report/identification/identified.json \
    --params-out report/identification/identified.toml --report report/identification

echo
echo "== 4. Diagnosis: the paper's campaign with a hidden 15 t, 6 Hz specimen"
HIDDEN="specimen:mass_kg=15000,frequency_hz=6,damping_ratio=0.03"
"$BIN" campaign synth --quiet --force --seed 7 --effect "$HIDDEN" report/hidden_campaign
mkdir -p report/diagnosis
"$BIN" diagnose report/hidden_campaign --json report/diagnosis/diagnosis.json \
    --params-out report/diagnosis/extended.toml --report report/diagnosis
echo "hidden truth: $HIDDEN"

echo
echo "== done: report/frf (analytic FRF), report/fmu (FRF through the FMU),"
echo "   report/identification/index.html, report/diagnosis/index.html"
