#!/usr/bin/env bash
# The diagnosis speed campaigns (README, "Performance": one hidden effect, full-length
# paper campaign, target under 60 s on 2 cores): synthesises each once into DIR/c/ and
# times `shaketable diagnose` on it, writing DIR/TAG/<seed>.json, .trace and a summary.
#
#   scripts/dev/speed.sh DIR TAG [SEED ...]     (default: all seven)
#
# Run it on an idle machine: a test suite beside it doubles the times.
set -euo pipefail
bin="$(cd "$(dirname "$0")/../.." && pwd)/target/release/shaketable"
dir="$1"; tag="$2"; shift 2
seeds=("$@"); [ ${#seeds[@]} -gt 0 ] || seeds=(451 452 453 454 456 458 459)

effect_of() {
    case "$1" in
        451) ;;
        452) echo "--effect specimen:mass_kg=15000,frequency_hz=4.5" ;;
        453) echo "--effect foundation:frequency_hz=12" ;;
        454) echo "--effect stick_slip:static_ratio=2.5" ;;
        456) echo "--effect valve_deadband:deadband=0.03" ;;
        458) echo "--effect flow_asymmetry:ratio=1.25" ;;
        459) echo "--effect free_play:gap_m=0.0005" ;;
        *) echo "unknown speed seed $1" >&2; exit 2 ;;
    esac
}

mkdir -p "$dir/c" "$dir/$tag"
: > "$dir/$tag/summary"
for seed in "${seeds[@]}"; do
    c="$dir/c/$seed"
    if [ ! -f "$c/campaign.toml" ]; then
        # shellcheck disable=SC2046
        "$bin" campaign synth --quiet --seed "$seed" $(effect_of "$seed") "$c"
    fi
    start=$(date +%s.%N)
    SHAKETABLE_TRACE=1 "$bin" diagnose --quiet --force --json "$dir/$tag/$seed.json" "$c" \
        > "$dir/$tag/$seed.out" 2> "$dir/$tag/$seed.trace"
    secs=$(echo "$(date +%s.%N) - $start" | bc)
    line=$(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); \
print([c['effect'] for c in d.get('causes',[])], 'explained', d.get('explained'))" "$dir/$tag/$seed.json")
    printf '%s %6.1f s %s\n' "$seed" "$secs" "$line" | tee -a "$dir/$tag/summary"
done
