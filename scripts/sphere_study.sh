#!/usr/bin/env bash
# The sphere-detection study of docs/results.md: scenes/dome.toml rendered under 48 lights at
# three resolutions, each capture made camera-like (sRGB, Gaussian noise in 8-bit codes,
# JPEG at several qualities, by oiiotool), then `rfd capture calibrate` finds the spheres by
# itself and is compared with the lights the stage used. Prints a markdown table of mean and
# worst angular errors, then the same for lamps near the scene (a dome of 600 mm radius)
# with the lamps placed from both spheres. About 35 minutes on two cores.
# Usage: scripts/sphere_study.sh RFD_BINARY OUTPUT_DIR
set -euo pipefail
rfd="$1"
out="$2"
scene="$(dirname "$0")/../scenes/dome.toml"
mkdir -p "$out"
vfov_deg=9.7  # scenes/dome.toml's camera
resolutions=(612x408 1224x816 2448x1632)
noises=(0 2 4)          # standard deviation, 8-bit codes
qualities=(png 95 85 70)

source "$(dirname "$0")/camera_like.sh"

echo "| resolution | noise (codes) | PNG mean / worst | JPEG q95 | JPEG q85 | JPEG q70 |"
echo "|---|---|---|---|---|---|"
for resolution in "${resolutions[@]}"; do
  field="$out/render_$resolution"
  if [ ! -f "$field/field.lp" ]; then
    "$rfd" --quiet capture render "$scene" --lights 48 --resolution "$resolution" --out "$field" > /dev/null
  fi
  height=${resolution#*x}
  focal=$(awk "BEGIN{printf \"%.4f\", ($height / 2) / (sin($vfov_deg * 3.14159265358979 / 360) / cos($vfov_deg * 3.14159265358979 / 360))}")
  for noise in "${noises[@]}"; do
    row="| $resolution | $noise |"
    for quality in "${qualities[@]}"; do
      capture="$out/capture_${resolution}_n${noise}_$quality"
      degrade "$field" "$capture" "$noise" "$quality"
      ext=jpg
      [ "$quality" = png ] && ext=png
      "$rfd" --quiet capture calibrate "$capture"/field_*."$ext" --focal-length-px "$focal" \
        --out "$capture/lights.lp" --compare "$field/field.lp" --json > "$capture/calibrate.json" 2> "$capture/calibrate.log" \
        || { row="$row failed |"; continue; }
      cell=$(awk '/"error_deg"/{f=1} f&&/"mean"/{gsub(/[",]/,"");m=$2} f&&/"worst"/{gsub(/[",]/,"");w=$2; printf "%.2f / %.2f", m, w; exit}' "$capture/calibrate.json")
      row="$row $cell |"
      rm -f "$capture"/field_*."$ext"
    done
    echo "$row"
  done
done

# The camera's model matters: the same 1 Mpx capture with the camera taken as distant.
capture="$out/orthographic_1224x816"
degrade "$out/render_1224x816" "$capture" 2 85
"$rfd" --quiet capture calibrate "$capture"/field_*.jpg --out "$capture/lights.lp" \
  --compare "$out/render_1224x816/field.lp" --json > "$capture/calibrate.json" 2> "$capture/calibrate.log" || true
echo
echo "1224x816, noise 2, JPEG q85, camera taken as distant (no focal length):" \
  "$(awk '/"error_deg"/{f=1} f&&/"mean"/{gsub(/[",]/,"");m=$2} f&&/"worst"/{gsub(/[",]/,"");w=$2; printf "mean %.2f, worst %.2f deg", m, w; exit}' "$capture/calibrate.json")"
rm -f "$capture"/field_*.jpg

# Near lamps, as a dome's of 600 mm radius: the spheres see each lamp from directions up to
# 20 degrees apart. The light file's directions, from the object, without and with
# --near-lamps (the lamp placed from both spheres), against the nominal directions.
near="$out/render_near_1224x816"
if [ ! -f "$near/field.lp" ]; then
  "$rfd" --quiet capture render "$scene" --lights 48 --resolution 1224x816 --dome-radius-mm 600 --out "$near" > /dev/null
fi
capture="$out/near_1224x816"
degrade "$near" "$capture" 2 85
focal=$(awk "BEGIN{printf \"%.4f\", 408 / (sin($vfov_deg * 3.14159265358979 / 360) / cos($vfov_deg * 3.14159265358979 / 360))}")
for flag in "" --near-lamps; do
  "$rfd" --quiet capture calibrate "$capture"/field_*.jpg --focal-length-px "$focal" --sphere-diameter-mm 24 $flag \
    --out "$capture/lights$flag.lp" --compare "$near/field.lp" --json > "$capture/calibrate$flag.json" \
    2> "$capture/calibrate$flag.log" || true
  echo "near lamps at 600 mm, 1224x816, noise 2, JPEG q85, ${flag:-distant model}:" \
    "$(awk '/"error_deg"/{f=1} f&&/"mean"/{gsub(/[",]/,"");m=$2} f&&/"worst"/{gsub(/[",]/,"");w=$2; printf "mean %.2f, worst %.2f deg", m, w; exit}' "$capture/calibrate$flag.json")"
done
echo "lamp distances placed from the spheres (mm; true 600):" \
  "$(grep -o '"distance": [0-9.]*' "$capture/calibrate--near-lamps.json" | awk '{print $2}' | sort -n | awk '{a[NR]=$1} END{printf "median %.0f, from %.0f to %.0f", a[int((NR+1)/2)], a[1], a[NR]}')"
rm -f "$capture"/field_*.jpg
