#!/usr/bin/env bash
# README command 2: set up and run every test (Rust unit + integration tests, pytest with fmpy).
# Everything runs in the release profile so the dependencies are compiled once.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
source scripts/setup.sh

echo "== cargo build (release)"
cargo build --release --all-targets --locked
if [ -x scripts/build_fmu.sh ]; then
  echo "== FMU"
  scripts/build_fmu.sh
fi
echo "== cargo test (release)"
cargo test --release --locked -- --test-threads=2
if compgen -G "tests/python/test_*.py" >/dev/null; then
  echo "== pytest"
  "$ROOT/.venv/bin/python" -m pytest -q tests/python
fi
echo "== all tests passed"
