#!/usr/bin/env bash
# README command 2: set up and run every test (Rust unit + integration tests, pytest with fmpy).
# Everything runs in the release profile so the dependencies are compiled once.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
# each phase prints the seconds since the start, so a slow CI run shows where it went
phase() { echo "== $1 (at ${SECONDS} s)"; }
source scripts/setup.sh

phase "cargo build (release)"
cargo build --release --all-targets --locked
if [ -x scripts/build_fmu.sh ]; then
  phase "FMU"
  scripts/build_fmu.sh
fi
phase "cargo test (release)"
cargo test --release --locked -- --test-threads=2
if compgen -G "tests/python/test_*.py" >/dev/null; then
  phase "pytest"
  "$ROOT/.venv/bin/python" -m pytest -q tests/python
fi
phase "all tests passed"
