#!/usr/bin/env bash
# make studies: the research reproductions behind docs/results.md, on the bundled scenes:
# the sampling study (thesis chapters 4-5), implicit relighting's eta trade-off (chapter 7),
# feature-guided upsampling against linear blending (chapter 6) and the tone and pitch
# calibrations' limits (rfd calibrate). About 14 minutes on two cores. Writes
# OUTPUT_DIR/INDEX.md.
# Usage: scripts/studies.sh RFD_BINARY OUTPUT_DIR
set -euo pipefail
rfd="$1"
out="$2"
source "$(dirname "$0")/index.sh"
index_begin "$out" "rfd studies" \
  "What \`make studies\` wrote: the measurements docs/results.md quotes. Paths are relative to this folder."

# Source fields (thesis chapters 4-5) on the default scene, the bottle: a near-uniform light
# pattern, then the sampling study: a 4096-direction reference, fixed patterns of 256 to 1025
# directions against adaptive sampling (error_vs_images.png, figure 5.5's analogue; per-
# direction error maps, figure 5.4's), and narrow against wide light kernels at n = 256.
# Images at 128x64 keep the study to a few minutes on two cores.
index_section capture "Sampling study: the bottle"
mkdir -p "$out/capture"
"$rfd" capture pattern --count 256 --out "$out/capture/pattern_256.lp" | tee "$out/capture/pattern.txt"
"$rfd" capture study scenes/bottle.toml --resolution 128x64 --out "$out/capture/study" \
  | tee "$out/capture/study.txt"

# Implicit relighting (thesis chapter 7) on the snooker scene: 272 overlapping smooth
# training lights captured as HDR (camera noise 1e-4) and 16 held-out lights photographed in
# one 8-bit exposure (noise 3e-3: the regime where eta matters, the new probe noisier than
# the training set), the model trained from the black ball, a prediction under a designed
# light, and PSNR against eta on the held-out lights (figure 7.3's trade-off) with pictures
# truth | eta = 0 | best eta | largest eta. About 80 s on 2 cores.
index_section implicit "Implicit relighting: the snooker scene"
implicit="$out/implicit"
mkdir -p "$implicit"
"$rfd" capture implicit scenes/snooker.toml --out "$implicit/set" | tee "$implicit/capture.txt"
"$rfd" relight implicit train "$implicit/set/training" --out "$implicit/model" | tee "$implicit/train.txt"
"$rfd" relight implicit predict "$implicit/model" --light 50,200,8 --out "$implicit/designed_light.png" \
  --probe-out "$implicit/designed_light_probe.png" | tee "$implicit/predict.txt"
"$rfd" relight implicit sweep "$implicit/model" --test "$implicit/set/test" --out "$implicit/eta" \
  | tee "$implicit/eta_sweep.txt"

# Feature-guided upsampling (thesis chapter 6) on the spheres scene (diffuse, chrome and
# glass spheres on a card) at 256 x 160, 8 samples per pixel: 256 stage lights upsampled one
# level (987 directions), scored against 512 other rendered lights at their own directions
# and under 15-degree area lights, with linear blending of the 256 beside it. Pictures per
# light (the field relit | the truth) for linear blending (linear/) and the upsampled field
# (upsampled/), at four point lights and under four area lights, both rendered by the stage
# itself (an area light as about 200 directions 1.2 degrees apart over its cap,
# scripts/cap_lights.awk). Below about 2 pixels (128 x 80 at 4 samples) the chrome
# ball's reflection of the light is a single noisy pixel and no method can place it; the
# gain then shrinks to a few tenths of a dB. About 5 minutes on 2 cores.
index_section upsample "Upsampling: the spheres"
upsample="$out/upsample"
mkdir -p "$upsample"
stage=(--resolution 256x160 --samples-per-pixel 8)
"$rfd" capture render scenes/spheres.toml --lights 256 "${stage[@]}" --out "$upsample/field_256" \
  > "$upsample/field_256.txt"
"$rfd" capture render scenes/spheres.toml --lights 512 "${stage[@]}" --out "$upsample/reference_512" \
  > "$upsample/reference_512.txt"
"$rfd" relight upsample "$upsample/field_256" --levels 1 --guard-tile 0 --out "$upsample/upsampled" | tee "$upsample/upsample.txt"
point_lights=(20,10 35,100 50,200 65,300)
area_lights=(30,0,7.5 30,120,7.5 60,60,7.5 60,240,7.5)
# The truth at the point lights: the stage renders exactly those directions.
{
  echo "${#point_lights[@]}"
  for light in "${point_lights[@]}"; do
    echo "$light" | awk -F, '{ t = $1 * atan2(0, -1) / 180; p = $2 * atan2(0, -1) / 180;
      printf "light_%s_%s %.17g %.17g %.17g\n", $1, $2, sin(t) * cos(p), sin(t) * sin(p), cos(t) }'
  done
} > "$upsample/point_lights.lp"
"$rfd" capture render scenes/spheres.toml --lights "$upsample/point_lights.lp" "${stage[@]}" \
  --out "$upsample/truth_points" > /dev/null
# The truth under the area lights: the stage renders their caps densely.
printf '%s\n' "${area_lights[@]}" | awk -v step=1.2 -f scripts/cap_lights.awk > "$upsample/area_lights.lp"
"$rfd" capture render scenes/spheres.toml --lights "$upsample/area_lights.lp" "${stage[@]}" \
  --out "$upsample/truth_area" > /dev/null
for method in linear upsampled; do
  field="$upsample/field_256"
  if [ "$method" = upsampled ]; then field="$upsample/upsampled"; fi
  "$rfd" relight eval "$field" --reference "$upsample/reference_512" > "$upsample/eval_${method}_directions.txt"
  point_args=() area_args=()
  for light in "${point_lights[@]}"; do point_args+=(--light "$light"); done
  for light in "${area_lights[@]}"; do area_args+=(--light "$light"); done
  "$rfd" relight eval "$field" --reference "$upsample/truth_points" "${point_args[@]}" \
    --out "$upsample/$method/point_lights" > "$upsample/eval_${method}_point_lights.txt"
  "$rfd" relight eval "$field" --reference "$upsample/truth_area" "${area_args[@]}" \
    --out "$upsample/$method/area_lights" > "$upsample/eval_${method}_area_lights.txt"
  for kind in directions point_lights area_lights; do
    echo "$method, $kind: $(grep -m1 PSNR "$upsample/eval_${method}_${kind}.txt" | sed 's/^ *PSNR *//')"
  done
done | tee "$upsample/summary.txt"

# The printer's tone curve from simulated photographs of the step wedge (rfd calibrate): a
# printer of density 1.6 and gamma 1.7 behind the Epson profile (2.0, 2.2), photographed
# under one condition at a time pushed toward where it fails; per condition the curve's RMS
# error at the patches against the truth, or the refusal. About 1 minute.
index_section tone "Tone calibration: where it stops"
tone="$out/tone"
mkdir -p "$tone"
printf '[printer]\nname = "true"\ndpi_x = 2880\ndpi_y = 1440\ngamma = 1.7\nmax_density = 1.6\nblack_level = 0.03\n' \
  > "$tone/true.toml"
tone_case() {  # NAME "CALIBRATE ARGS" SIMULATE ARGS...
  local name="$1" calibrate_args="$2"
  shift 2
  "$rfd" --quiet calibrate simulate-photo wedge epson_stylus_pro_4800 --true-printer "$tone/true.toml" "$@" \
    --out "$tone/$name.jpg" > /dev/null
  # shellcheck disable=SC2086  # the calibration's options, split on purpose
  if message=$("$rfd" --quiet calibrate tone epson_stylus_pro_4800 "$tone/$name.jpg" $calibrate_args \
      --out "$tone/$name.toml" --report "$tone/$name" 2>&1); then
    awk -F, -v name="$name" 'NR > 1 { ink = 10 ^ -1.6; t = ink + (1 - ink) * (1 - $2) ^ 1.7; d = $8 - t; s += d * d; n++ }
      END { printf "%-14s curve RMS %.4f\n", name, sqrt(s / n) }' "$tone/$name/tone.csv"
  else
    printf '%-14s refused: %s\n' "$name" "$(echo "$message" | tail -1 | sed 's/^rfd: error: [^:]*: //')"
  fi
}
{
  for tilt in 0 30 45 60 70; do tone_case "tilt_$tilt" "" --camera-tilt "$tilt" --camera-turn 30 --blur 1 --photons 3000 --frame-fill 0.6; done
  for blur in 2 4 8; do tone_case "blur_$blur" "" --blur "$blur" --photons 3000; done
  for photons in 30 100 300; do tone_case "photons_$photons" "" --photons "$photons"; done
  tone_case vignetting_0.8 "" --vignetting 0.8 --photons 3000
  tone_case from_back "" --from-back --camera-tilt 30 --camera-roll 180 --frame-fill 0.7 --photons 3000
  tone_case reflected "--light reflected" --light reflected --photons 3000
  tone_case small "" --frame-fill 0.1
} | tee "$tone/summary.txt"

# The lens array's pitch from simulated photographs of the moire sheet mounted in Design I
# (rfd calibrate pitch): the array 0.1 % too large and turned 0.3 deg, one condition at a time
# pushed toward where it fails, the rest a mild phone (blur 1 px, 3000 photons, JPEG 80); per
# condition the pitch's and row spacing's error against the truth (%), with the stated
# uncertainty, and the turn's (deg), or the refusal. About 2 minutes.
index_section pitch "Pitch calibration: where it stops"
pitch="$out/pitch"
mkdir -p "$pitch"
pitch_case() {  # NAME CAMERA_PIXELS SIMULATE ARGS...
  local name="$1" pixels="$2"
  shift 2
  "$rfd" --quiet calibrate simulate-photo moire epson_stylus_pro_4800 --design designs/design1.toml \
    --pitch-error 0.001 --array-rotation 0.3 --camera-pixels "$pixels" "$@" --out "$pitch/$name.jpg" > /dev/null
  if message=$("$rfd" --quiet calibrate pitch designs/design1.toml "$pitch/$name.jpg" 2>&1); then
    echo "$message" | awk -v name="$name" '
      /rows turned/ { for (i = 1; i <= NF; i++) if ($i == "turned") turn = $(i + 1) - 0.3 }
      /^pitch along a row/ { x = $(NF - 4) - 0.1; sx = $(NF - 1) }
      /^row spacing/ { y = $(NF - 4) - 0.1; sy = $(NF - 1) }
      END { printf "%-16s pitch %+.4f %% (+- %s), rows %+.4f %% (+- %s), turn %+.4f deg\n", name, x, sx, y, sy, turn }'
  else
    printf '%-16s refused: %s\n' "$name" "$(echo "$message" | tail -1 | sed 's/^rfd: error: [^:]*: //')"
  fi
}
{
  for tilt in 0 30 45 60; do pitch_case "tilt_$tilt" 3000 --camera-tilt "$tilt" --camera-turn 30 --frame-fill 0.7 --blur 1 --photons 3000; done
  for blur in 2 4 8; do pitch_case "blur_$blur" 3000 --blur "$blur" --photons 3000; done
  for photons in 30 100 300; do pitch_case "photons_$photons" 3000 --blur 1 --photons "$photons"; done
  for sun in 10 20 25 28 30; do pitch_case "sun_$sun" 3000 --light-tilt "$sun" --light-turn 40 --blur 1 --photons 3000; done
  pitch_case hand_uneven 3000 --camera-tilt 30 --camera-turn 50 --blur 1.5 --vignetting 0.35 --photons 2000 \
    --light-tilt 10 --light-turn 120
  for pixels in 2000 1500 1000; do pitch_case "pixels_$pixels" "$pixels" --blur 1 --photons 3000; done
  pitch_case shifted_20mm 3000 --array-shift 0,-20 --blur 1 --photons 3000
  pitch_case off_the_bands 3000 --array-shift 0,150 --blur 1 --photons 3000
} | tee "$pitch/summary.txt"

# Design II's 6 x 5 array, laid whole on each measuring band in turn and photographed hand-held
# on each (blur 1.2 px, 30 % vignetting, 2500 photons, JPEG 80, 4000 pixels): 16 placements
# drawn at random (pitch errors within +-0.2 % per axis, turns within +-1 deg, the array up to
# 2.5 mm off the band's middle, the camera 22-35 deg off the vertical from any side, rolled up
# to 15 deg), then one placement turned from -1.5 to +1.5 deg in steps of 0.1. Per case the
# pitch's and row spacing's error against the truth (%) with the stated uncertainty, or the
# refusal. About 3 minutes. The bands are graded (print/moire.cpp).
index_section pitch_small "Pitch calibration: Design II's small array"
small="$out/pitch_small"
mkdir -p "$small"
small_case() {  # NAME PITCH_ERROR PITCH_ERROR_Y TURN SHIFT_X SHIFT_Y TILT CAMERA_TURN ROLL SEED
  local name="$1" ex="$2" ey="$3" turn="$4" sx="$5" sy="$6" tilt="$7" azimuth="$8" roll="$9" seed="${10}"
  for band in x rows; do
    "$rfd" --quiet calibrate simulate-photo moire epson_stylus_pro_4800 --design designs/design2.toml \
      --array-on "$band" --pitch-error "$ex" --pitch-error-y "$ey" --array-rotation "$turn" --array-shift "$sx,$sy" \
      --camera-tilt "$tilt" --camera-turn "$azimuth" --camera-roll "$roll" --camera-distance 520 --frame-fill 0.78 \
      --camera-pixels 4000 --blur 1.2 --vignetting 0.3 --photons 2500 --seed "$seed" \
      --out "$small/${name}_$band.jpg" > /dev/null
  done
  if message=$("$rfd" --quiet calibrate pitch designs/design2.toml "$small/${name}_x.jpg" "$small/${name}_rows.jpg" 2>&1); then
    echo "$message" | awk -v name="$name" -v ex="$ex" -v ey="$ey" '
      /^pitch along a row/ { x = $(NF - 4) - 100 * ex; sx = $(NF - 1) }
      /^row spacing/ { y = $(NF - 4) - 100 * ey; sy = $(NF - 1) }
      END { printf "%-10s pitch %+.4f %% (+- %s), rows %+.4f %% (+- %s)\n", name, x, sx, y, sy }'
  else
    printf '%-10s refused: %s\n' "$name" "$(echo "$message" | tail -1 | sed "s|^rfd: error: $small/||")"
  fi
}
{
  k=0
  while read -r ex ey turn sx sy tilt azimuth roll; do
    k=$((k + 1))
    small_case "placed_$k" "$ex" "$ey" "$turn" "$sx" "$sy" "$tilt" "$azimuth" "$roll" "$k"
  done <<'CASES'
-0.0007 -0.0014 0.3 -2.14 0.18 26.8 -159 0
-0.00185 -0.00027 -0.86 -2.05 -0.38 32.7 -135 -8
0.00051 0.00179 0.15 -0.52 2.38 22.6 129 -6
-0.00142 -0.00153 -0.38 1.58 -1.6 29.6 50 -4
0.00019 -0.00175 -0.88 -1.47 0.9 27.6 -67 3
-0.00019 -0.0008 0.59 0.99 -1.28 29.5 9 11
0.00092 -0.00085 0.96 -1.91 -0.41 31.8 -125 0
-0.00184 0.00067 0.53 0.37 1.88 26.1 70 3
0.00032 -0.00018 0.68 2.22 -0.13 30.6 -158 6
0.00059 0.00197 0.64 -1.08 -0.57 30.7 -172 -1
-0.00133 -0.00153 -0.88 1.34 -1.85 25.2 -39 11
-0.00168 -0.0002 0.1 1.92 1.6 33.2 -80 -3
-0.00056 0.00154 0.92 -1.75 -1.62 25 -96 0
0.00036 -0.00095 -0.99 -0.41 -0.65 29.4 163 6
0.00006 0.00047 0.35 -2.23 2 32.1 135 9
-0.00043 -0.0004 -0.79 0.67 -2.19 22.9 -105 -10
CASES
  for turn in $(seq -1.5 0.1 1.5); do
    small_case "turn_$turn" 0.0007 -0.0011 "$turn" 0.8 -0.6 28 -150 4 3
  done
} | tee "$small/summary.txt"

index_entry capture/study/error_vs_images.png "the bottle's sampling study: error against image count for fixed patterns of 256 to 1025 directions and adaptive sampling (figure 5.5's analogue; study.txt: the table, study/: per-direction error maps)"
index_entry capture/pattern_256.lp "a near-uniform pattern of 256 light directions for a real light stage (pattern.txt: how even)"
index_entry implicit/eta/eta_psnr.png "implicit relighting on the snooker scene: PSNR of the held-out lights against eta (figure 7.3's trade-off; eta_sweep.txt: the numbers, eta/light_*.png: truth | eta 0 | best | largest)"
index_entry implicit/designed_light.png "the scene relit from the trained model under a designed 8-degree light (designed_light_probe.png: the synthetic probe)"
index_entry upsample/summary.txt "upsampling 256 stage lights of the spheres one level against linear blending: PSNR at 512 other directions, four point lights and four area lights"
index_entry pitch/summary.txt "the lens array's pitch from simulated photographs of the moire sheet in Design I: the pitch's, row spacing's and turn's errors (or the refusal) as tilt, blur, noise, the sun's slant, resolution and placement push toward failure"
index_entry pitch_small/summary.txt "Design II's 6 x 5 array laid whole on each band: the pitch's and row spacing's errors (or the refusal) over 16 random hand-held placements and 31 turns of the array"
index_entry tone/summary.txt "the printer's tone curve from simulated photographs of its wedge: the curve's RMS error (or the refusal) as tilt, blur, noise, vignetting, the film's side and the light push toward failure"
index_entry upsample/upsampled/point_lights "pictures per point light, the upsampled field relit | the stage's truth (linear/: the same for linear blending; area_lights/ under area lights)"

index_end
