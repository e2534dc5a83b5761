#!/usr/bin/env bash
# Set up a fresh Debian machine (Rust toolchain and Python 3.11 with pip already there):
# the Debian packages the build needs, and the pinned Python venv in .venv/.
# Idempotent and quiet when everything is in place. Sourced by run.sh and test.sh.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# libclang-dev: fmi-sys builds its FMI 2.0 bindings with bindgen.
# binutils: readelf/nm, with which the tests read the FMU binary's symbols.
# libfontconfig1-dev, libfreetype-dev, pkg-config, fonts-dejavu-core: plotters draws text.
DEB_PACKAGES=(libclang-dev binutils libfontconfig1-dev libfreetype-dev pkg-config fonts-dejavu-core)
missing=()
for p in "${DEB_PACKAGES[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -q
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${missing[@]}"
fi

# Python venv with the pinned tools (fmpy, numpy, scipy, pytest, matplotlib).
PY="${PYTHON:-python3.11}"
command -v "$PY" >/dev/null 2>&1 || PY=python3
VENV="$ROOT/.venv"
STAMP="$VENV/.requirements.stamp"
if [ ! -x "$VENV/bin/python" ]; then
  echo "setup: creating Python venv in .venv"
  "$PY" -m venv "$VENV"
fi
if ! cmp -s "$ROOT/scripts/requirements.txt" "$STAMP" 2>/dev/null; then
  echo "setup: installing scripts/requirements.txt into .venv"
  "$VENV/bin/pip" install -q --disable-pip-version-check -r "$ROOT/scripts/requirements.txt"
  cp "$ROOT/scripts/requirements.txt" "$STAMP"
fi
