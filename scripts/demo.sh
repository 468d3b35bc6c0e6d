#!/usr/bin/env bash
# The main job on the bundled defaults: for each of Designs I-IV, the system summary and
# the speed-versus-accuracy chart of the paraxial model against the exact tracer; then the
# sampling study of the source-field work on the bottle scene.
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

# Source fields (thesis chapters 4-5) on the default scene, the bottle: a near-uniform light
# pattern, then the sampling study: a 4096-direction reference, fixed patterns of 256 to 1025
# directions against adaptive sampling (error_vs_images.png, figure 5.5's analogue; per-
# direction error maps, figure 5.4's), and narrow against wide light kernels at n = 256.
# Images at 128x64 keep the study to a few minutes on two cores.
mkdir -p "$out/capture"
echo "== scenes/bottle.toml: sampling study" >&2
"$rfd" capture pattern --count 256 --out "$out/capture/pattern_256.lp" | tee "$out/capture/pattern.txt"
"$rfd" capture study scenes/bottle.toml --resolution 128x64 --out "$out/capture/study" \
  | tee "$out/capture/study.txt"

echo "demo written to $out" >&2
