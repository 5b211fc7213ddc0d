#!/usr/bin/env bash
# The cost of banded gases ([gases]: the k-distribution's terms, crates/sora/src/sky/k_terms.rs)
# against the same atmosphere without them, whole process, release CLI.
#
#   scripts/bench/gases.sh [SORA] [RUNS]
#
# SORA: the binary (default target/release/sora; build it with cargo build --release -p sora-cli).
# Two cases, each with and without gases, RUNS runs each (default 5), alternating:
#   spectrum: one almucantar (36 views, every 10 degrees at the sun's elevation), sun 30 degrees,
#             900-1000 nm every 10 nm (the 940 nm water band: every sample absorbs)
#             sora spectrum --atmosphere A --sun-elevation 30 --wavelengths 900:1000:10 --almucantar 10
#   render:   a 256 x 256 fisheye image, 380-780 nm every 20 (the default grid), sun 30 degrees
#             sora render --atmosphere A --sun-elevation 30 --camera fisheye --width 256 --height 256 -o x.exr
#             (a sky for colour images: the terms merged where colour allows, sky/k_terms.rs)
# The atmospheres: earth-clear-summer-no-aerosol (crates/sora-cli/tests/data/measured/), with its
# [gases] (precipitable_water_cm = 2.92, o2_o2 = true) and with that table removed.
# Prints the median user + system CPU seconds (GNU time) of each and their ratio.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
sora=${1:-$root/target/release/sora}
runs=${2:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
gas=$root/crates/sora-cli/tests/data/measured/earth-clear-summer-no-aerosol.toml
sed '/^\[gases\]/,$d' "$gas" > "$work/nogas.toml"
grep -q '^\[gases\]' "$gas"
median() { sort -g | awk '{v[NR]=$1} END {print (NR % 2) ? v[(NR+1)/2] : (v[NR/2] + v[NR/2+1]) / 2}'; }
cpu() { /usr/bin/time -f '%U %S' -o "$work/t" "$@" > /dev/null 2>&1; awk '{print $1 + $2}' "$work/t"; }
run_case() {
    local name=$1; shift
    : > "$work/with"; : > "$work/without"
    for _ in $(seq "$runs"); do
        cpu "$sora" "$@" --atmosphere "$gas" >> "$work/with"
        cpu "$sora" "$@" --atmosphere "$work/nogas.toml" >> "$work/without"
    done
    local a b
    a=$(median < "$work/with"); b=$(median < "$work/without")
    printf '%-9s with gases %6.3f s  without %6.3f s  ratio %5.2f  (median CPU s of %d)\n' \
        "$name" "$a" "$b" "$(echo "$a / $b" | bc -l)" "$runs"
}
run_case spectrum spectrum --sun-elevation 30 --wavelengths 900:1000:10 --almucantar 10
run_case render render --sun-elevation 30 --camera fisheye --width 256 --height 256 -o "$work/x.exr"
