#!/usr/bin/env bash
# The main job on the bundled defaults: for each of Designs I-IV, the system summary and
# the speed-versus-accuracy chart of the paraxial model against the exact tracer.
# Usage: scripts/demo.sh RFD_BINARY OUTPUT_DIR
set -euo pipefail
rfd="$1"
out="$2"
mkdir -p "$out"

for n in 1 2 3 4; do
  design="designs/design$n.toml"
  dir="$out/design$n"
  mkdir -p "$dir"
  echo "== $design" >&2
  "$rfd" design show "$design" | tee "$dir/summary.txt"
  "$rfd" design show "$design" --json > "$dir/summary.json"
  "$rfd" optics chart "$design" --out "$dir/chart" | tee "$dir/chart.txt"
done

mkdir -p "$out/lenses"
for lens in designs/lenses/*.toml; do
  name="$(basename "$lens" .toml)"
  "$rfd" optics system "$lens" > "$out/lenses/$name.txt"
  "$rfd" optics trace "$lens" --angle 5 >> "$out/lenses/$name.txt"
done

echo "demo written to $out" >&2
