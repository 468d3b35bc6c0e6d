#!/usr/bin/env bash
# The guarded-upsampling study of docs/results.md: captures as a handheld kit takes them (40
# irregular lights, none within 15 degrees of the zenith; sRGB, noise of 2 codes, JPEG
# quality 90) of three bundled scenes; every fourth light held out in turn, the rest
# upsampled one level (`rfd relight upsample`, with its guard and without) and blended
# (Delaunay), the held-out light relit from each and compared with its photograph (PSNR in
# 8-bit sRGB codes, oiiotool). Prints per scene the gain over blending, mean and worst, and
# the lights where upsampling loses more than 0.1 dB. About 40 minutes on 2 cores.
# Usage: scripts/upsample_study.sh RFD_BINARY OUTPUT_DIR
set -euo pipefail
rfd="$1"
out="$2"
scenes_dir="$(dirname "$0")/../scenes"
source "$(dirname "$0")/camera_like.sh"
mkdir -p "$out"
handheld_lights 40 7 "$out/handheld.lp"

psnr() { oiiotool --diff "$1" "$2" 2>/dev/null | awk '/Peak SNR/ {print $4}'; }

echo "| scene | held out | guarded: mean / worst gain over blending (dB) | lights worse than -0.1 dB | unguarded: mean / worst | worse than -0.1 dB |"
echo "|---|---|---|---|---|---|"
for scene in spheres figure bottle; do
  field="$out/render_$scene"
  [ -f "$field/field.lp" ] || "$rfd" --quiet capture render "$scenes_dir/$scene.toml" --lights "$out/handheld.lp" \
    --resolution 200x150 --out "$field" > /dev/null
  capture="$out/capture_$scene"
  [ -f "$capture/field.lp" ] || degrade "$field" "$capture" 2 90
  : > "$capture/gains.txt"
  for j in $(seq 0 4 39); do
    line=$((j + 2))
    awk -v skip="$line" 'NR == 1 {print $1 - 1; next} NR != skip {print}' "$capture/field.lp" > "$capture/minus_$j.lp"
    dir=$(sed -n "${line}p" "$capture/field.lp" | awk '{print $2 "," $3 "," $4}')
    truth="$capture/$(sed -n "${line}p" "$capture/field.lp" | awk '{print $1}')"
    "$rfd" --quiet relight upsample "$capture/minus_$j.lp" --levels 1 --out "$capture/up_$j" > /dev/null
    "$rfd" --quiet relight upsample "$capture/minus_$j.lp" --levels 1 --guard-tile 0 --out "$capture/raw_$j" > /dev/null
    "$rfd" --quiet relight render "$capture/up_$j" --light-dir "$dir" --out "$capture/pred_up_$j.png" > /dev/null
    "$rfd" --quiet relight render "$capture/raw_$j" --light-dir "$dir" --out "$capture/pred_raw_$j.png" > /dev/null
    "$rfd" --quiet relight render "$capture/minus_$j.lp" --light-dir "$dir" --out "$capture/pred_blend_$j.png" > /dev/null
    echo "$j $(psnr "$capture/pred_up_$j.png" "$truth") $(psnr "$capture/pred_raw_$j.png" "$truth") $(psnr "$capture/pred_blend_$j.png" "$truth")" \
      >> "$capture/gains.txt"
    rm -rf "$capture/up_$j" "$capture/raw_$j"
  done
  awk -v scene="$scene" '{ g = $2 - $4; r = $3 - $4; sg += g; sr += r; n++
                           if (n == 1 || g < wg) wg = g; if (n == 1 || r < wr) wr = r
                           if (g < -0.1) bg++; if (r < -0.1) br++ }
       END { printf "| %s | %d | %+.2f / %+.2f | %d | %+.2f / %+.2f | %d |\n", scene, n, sg / n, wg, bg, sr / n, wr, br }' \
    "$capture/gains.txt"
done
