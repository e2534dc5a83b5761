#!/usr/bin/env bash
# Build the FMI 2.0 FMU (Co-Simulation and Model Exchange), target/fmu/ShakeTable.fmu, and
# the FMI 3.0 Co-Simulation FMU beside it, target/fmu/ShakeTable3.fmu
#   scripts/build_fmu.sh                    # TREES Lab defaults as start values
#   scripts/build_fmu.sh --params lab.toml  # a lab's parameter file baked in
# The cdylib is built in release and packaged with modelDescription.xml (generated from
# the variable table, its GUID from the start values), documentation/index.html, model.png
# and resources/parameters.toml (the --params file, or the defaults written out; read by
# fmi2Instantiate, so the binary starts from the same values the XML declares).
# The binary is linked against glibc 2.17 (manylinux2014's baseline) with cargo-zigbuild,
# so it loads on RHEL 7/8, Ubuntu 18.04/20.04, Debian 9-11 and later, not only on the
# machine that built it (scripts/setup.sh installs zig and cargo-zigbuild into .venv).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
PARAMS=""
OUT="$ROOT/target/fmu/ShakeTable.fmu"
while [ $# -gt 0 ]; do
  case "$1" in
    --params) PARAMS="$(cd "$(dirname "$2")" && pwd)/$(basename "$2")"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    *) echo "build_fmu.sh: unknown option $1 (use --params FILE, --out FILE)" >&2; exit 2 ;;
  esac
done
cargo build --release --locked --bin shaketable
BIN="$ROOT/target/release/shaketable"
RUST_TARGET=x86_64-unknown-linux-gnu
GLIBC_BASELINE=2.17
export PATH="$ROOT/.venv/bin:$PATH"
if ! command -v cargo-zigbuild >/dev/null 2>&1; then
  echo "build_fmu.sh: cargo-zigbuild not found: run scripts/setup.sh (it installs zig and cargo-zigbuild into .venv)" >&2
  exit 2
fi
# bindgen (fmi-sys' build script) runs on this machine and needs its C headers, which
# zig's compiler wrapper hides from it
CLANG_INCLUDE="$(ls -d /usr/lib/llvm-*/lib/clang/*/include 2>/dev/null | sort -V | tail -1)"
MULTIARCH="$(gcc -print-multiarch 2>/dev/null || echo x86_64-linux-gnu)"
BINDGEN_EXTRA_CLANG_ARGS="-I$CLANG_INCLUDE -I/usr/include/$MULTIARCH -I/usr/include" \
  cargo zigbuild --release --locked --lib --target "$RUST_TARGET.$GLIBC_BASELINE"
SO="$ROOT/target/$RUST_TARGET/release/libshaketable.so"
mkdir -p "$(dirname "$OUT")"
OUT="$(cd "$(dirname "$OUT")" && pwd)/$(basename "$OUT")"
STAGE="$(dirname "$OUT")/.stage-$(basename "$OUT" .fmu)-$$"
mkdir -p "$STAGE/binaries/linux64" "$STAGE/documentation" "$STAGE/resources"
ARGS=()
if [ -n "$PARAMS" ]; then
  "$BIN" params --check "$PARAMS" > /dev/null
  ARGS=(--params "$PARAMS")
  cp "$PARAMS" "$STAGE/resources/parameters.toml"
else
  "$BIN" params --defaults > "$STAGE/resources/parameters.toml"
fi
# the build's time, or SOURCE_DATE_EPOCH's for a reproducible build
GENERATED_AT="$(date -u ${SOURCE_DATE_EPOCH:+-d @$SOURCE_DATE_EPOCH} +%Y-%m-%dT%H:%M:%SZ)"
"$BIN" fmu description "${ARGS[@]}" --generated-at "$GENERATED_AT" > "$STAGE/modelDescription.xml"
"$BIN" fmu documentation "${ARGS[@]}" > "$STAGE/documentation/index.html"
"$BIN" fmu icon --out "$STAGE/model.png"
cp "$SO" "$STAGE/binaries/linux64/ShakeTable.so"
zip_stage() {
  python3 - "$1" "$2" <<'PY'
import os, sys, zipfile
stage, out = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
    for d, _, files in sorted(os.walk(stage)):
        for f in sorted(files):
            p = os.path.join(d, f)
            z.write(p, os.path.relpath(p, stage))
PY
}
zip_stage "$STAGE" "$OUT"
echo "wrote $OUT"

# The FMI 3.0 Co-Simulation FMU beside it (same binary, which exports both APIs): its own
# description, the binary under FMI 3.0's platform tuple, the icon under terminalsAndIcons/.
OUT3="${OUT%.fmu}3.fmu"
STAGE3="$(dirname "$OUT")/.stage-$(basename "$OUT3" .fmu)-$$"
mkdir -p "$STAGE3/binaries/x86_64-linux" "$STAGE3/documentation" "$STAGE3/resources" "$STAGE3/terminalsAndIcons"
cp "$STAGE/resources/parameters.toml" "$STAGE3/resources/parameters.toml"
cp "$STAGE/documentation/index.html" "$STAGE3/documentation/index.html"
cp "$STAGE/model.png" "$STAGE3/terminalsAndIcons/icon.png"
cp "$SO" "$STAGE3/binaries/x86_64-linux/ShakeTable.so"
"$BIN" fmu description "${ARGS[@]}" --fmi-version 3 --generated-at "$GENERATED_AT" > "$STAGE3/modelDescription.xml"
zip_stage "$STAGE3" "$OUT3"
rm -rf "$STAGE" "$STAGE3"
echo "wrote $OUT3"
