#!/usr/bin/env bash
# The fitted-basis study of docs/results.md: the bundled scenes rendered by the virtual light
# stage under a dome's 48 lights and a handheld capture's 40 (irregular, none within 15
# degrees of the zenith), made camera-like (sRGB, noise of 2 codes, JPEG quality 90), then
# every image predicted from the others (`rfd relight eval --leave-one-out --basis all`) and
# `rfd relight fit --basis auto`'s choice against the best single fittable basis. Prints a
# markdown table of mean leave-one-out PSNR in 8-bit sRGB codes. About 5 minutes on 2 cores.
# Usage: scripts/basis_study.sh RFD_BINARY OUTPUT_DIR
set -euo pipefail
rfd="$1"
out="$2"
scenes_dir="$(dirname "$0")/../scenes"
source "$(dirname "$0")/camera_like.sh"
mkdir -p "$out"
handheld_lights 40 7 "$out/handheld.lp"

echo "| scene | lights | delaunay | ptm | hsh2 | hsh3 | hsh4 | rbf | bilinear | auto's choice | auto - best fittable |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for scene in bottle spheres figure snooker dome; do
  for lights in dome handheld; do
    field="$out/render_${scene}_$lights"
    light_arg=48
    [ "$lights" = handheld ] && light_arg="$out/handheld.lp"
    if [ ! -f "$field/field.lp" ]; then
      "$rfd" --quiet capture render "$scenes_dir/$scene.toml" --lights "$light_arg" --resolution 400x300 \
        --out "$field" > /dev/null
    fi
    capture="$out/capture_${scene}_$lights"
    [ -f "$capture/field.lp" ] || degrade "$field" "$capture" 2 90
    "$rfd" --quiet relight eval "$capture" --leave-one-out --basis all > "$capture/eval.txt"
    "$rfd" --quiet relight fit "$capture" --basis auto --out "$capture/fit" > "$capture/fit.txt"
    # "mean NAME [SIGMA] X dB Y dB SSIM": the 8-bit sRGB PSNR per basis.
    row="| $scene | $lights |"
    for basis in delaunay ptm hsh2 hsh3 hsh4 rbf bilinear; do
      row="$row $(awk -v b="$basis" '$1 == "mean" && $2 == b { for (i = 3; i <= NF; ++i) if ($(i + 1) == "dB") { print $i; exit } }' "$capture/eval.txt") |"
    done
    chosen=$(awk '/<- chosen/ {print $1}' "$capture/fit.txt")
    gap=$(awk -v c="$chosen" '$1 ~ /^(ptm|hsh2|hsh3|rbf|bilinear)$/ && $3 == "dB" { v[$1] = $2; if ($2 > best) best = $2 }
                              END { printf "%.2f", v[c] - best }' "$capture/fit.txt")
    echo "$row $chosen | $gap |"
  done
done
