#!/usr/bin/env bash
# The main job on the bundled defaults: for each of Designs I-IV, the system summary and
# the speed-versus-accuracy chart of the paraxial model against the exact tracer; then the
# sampling study of the source-field work on the bottle scene; implicit relighting on the
# snooker scene; feature-guided upsampling on the spheres scene; then the print patterns.
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

# Implicit relighting (thesis chapter 7) on the snooker scene: 272 overlapping smooth
# training lights captured as HDR (camera noise 1e-4) and 16 held-out lights photographed in
# one 8-bit exposure (noise 3e-3: the regime where eta matters, the new probe noisier than
# the training set), the model trained from the black ball, a prediction under a designed
# light, and PSNR against eta on the held-out lights (figure 7.3's trade-off) with pictures
# truth | eta = 0 | best eta | largest eta. About 80 s on 2 cores.
implicit="$out/implicit"
mkdir -p "$implicit"
echo "== implicit relighting: scenes/snooker.toml" >&2
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
upsample="$out/upsample"
mkdir -p "$upsample"
echo "== upsampling: scenes/spheres.toml" >&2
stage=(--resolution 256x160 --samples-per-pixel 8)
"$rfd" capture render scenes/spheres.toml --lights 256 "${stage[@]}" --out "$upsample/field_256" \
  > "$upsample/field_256.txt"
"$rfd" capture render scenes/spheres.toml --lights 512 "${stage[@]}" --out "$upsample/reference_512" \
  > "$upsample/reference_512.txt"
"$rfd" relight upsample "$upsample/field_256" --levels 1 --out "$upsample/upsampled" | tee "$upsample/upsample.txt"
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

# Patterns (thesis 8.4): the bottle's field encoded for Designs I and II at the thesis's
# 2880 x 1440 dpi, the light tilted by 45 degrees as the thesis did; and the "SIG08" letters
# of its Design II demonstration. Each pattern comes with a PNG preview.
patterns="$out/patterns"
mkdir -p "$patterns"
echo "== patterns: Designs I and II" >&2
"$rfd" capture render scenes/bottle.toml --lights 400 --resolution 128x64 --out "$patterns/bottle_field" \
  > "$patterns/bottle_field.txt"
for n in 1 2; do
  "$rfd" pattern encode "designs/design$n.toml" "$patterns/bottle_field" --tilt 45 \
    --out "$patterns/design${n}_bottle.exr" --preview "$patterns/design${n}_bottle.png" \
    | tee "$patterns/design${n}_bottle.txt"
done
"$rfd" pattern field letters --text SIG08 --resolution 48x40 --out "$patterns/sig08_field" > /dev/null
"$rfd" pattern encode designs/design2.toml "$patterns/sig08_field" --interpolation nearest \
  --out "$patterns/design2_sig08.exr" --preview "$patterns/design2_sig08.png" | tee "$patterns/design2_sig08.txt"

# Print sheets for the thesis's printer (8.4, 8.4.1): front and mirrored back sheets for
# back-to-back printing, registration markers under the corner lenslets, crop marks, ruler,
# label. Design I's full A4 page as TIFF (true 2880 x 1440 dpi tags), Design II's as PDF.
echo "== print sheets" >&2
"$rfd" print sheet designs/design1.toml "$patterns/design1_bottle.exr" --printer epson_stylus_pro_4800 \
  --out "$patterns/design1_front.tif" | tee "$patterns/design1_sheets.txt"
"$rfd" print sheet designs/design1.toml "$patterns/design1_bottle.exr" --printer epson_stylus_pro_4800 \
  --mirror --out "$patterns/design1_back.tif" | tee -a "$patterns/design1_sheets.txt"
for name in design2_bottle design2_sig08; do
  "$rfd" print sheet designs/design2.toml "$patterns/$name.exr" --out "$patterns/${name}_front.pdf" \
    | tee "$patterns/${name}_sheets.txt"
  "$rfd" print sheet designs/design2.toml "$patterns/$name.exr" --mirror --out "$patterns/${name}_back.pdf" \
    | tee -a "$patterns/${name}_sheets.txt"
done
"$rfd" print moire designs/design1.toml --pitch 2.350:2.366:9 --out "$patterns/design1_moire.pdf" \
  | tee "$patterns/design1_moire.txt"

# What the displays will show (thesis 8.2): Design I and II patterns of the bottle under a
# light on the display's axis (field theta 45, phi 90 with the 45-degree tilt) and one off
# it, a red and a green light together, and a disc light; each with the same lights
# relighting the field in software beside it for comparison.
predicted="$out/predicted"
mkdir -p "$predicted"
echo "== predicted display output" >&2
# An environment map for them: a dim blue-grey room (64 x 32, latitude-longitude, field
# frame) with a bright window around the display's axis (field theta 45, phi 90).
oiiotool --pattern constant:color=4,3.6,3.2 10x6 3 --pattern constant:color=0.04,0.05,0.07 64x32 3 \
  --paste +43+5 -d float -o "$predicted/window_room.exr"
for n in 1 2; do
  "$rfd" simulate "designs/design$n.toml" "$patterns/design${n}_bottle.exr" --envmap "$predicted/window_room.exr" \
    --out "$predicted/design${n}_window_room.png" --lenslets "$predicted/design${n}_window_room_lenslets.png" \
    | tee "$predicted/design${n}_window_room.txt"
done
for n in 1 2; do
  for case in "axis:--light 45,90" "side:--light 45,70" "red_green:--light 45,75,1:0:0 --light 45,105,0:1:0" \
              "disc:--light 45,90,8"; do
    name="${case%%:*}"
    samples=5
    if [ "$name" = disc ]; then samples=3; fi  # 9 directions over the disc
    # shellcheck disable=SC2086 # the lights are several words on purpose
    "$rfd" simulate "designs/design$n.toml" "$patterns/design${n}_bottle.exr" ${case#*:} \
      --area-samples "$samples" --out "$predicted/design${n}_${name}.png" --lenslets "$predicted/design${n}_${name}_lenslets.png" \
      | tee "$predicted/design${n}_${name}.txt"
    if [ "$n" = 1 ]; then
      # shellcheck disable=SC2086
      "$rfd" relight render "$patterns/bottle_field" ${case#*:} --out "$predicted/field_${name}.png" > /dev/null
    fi
  done
done
# How precisely to assemble Design II (issue 5): PSNR of the predicted picture against
# pattern shift, rotation, pitch error and spacer error, for a smooth and a sharp pattern.
# (Design I takes about two minutes: see the README's "Assembly tolerances".)
for pattern in bottle sig08; do
  "$rfd" simulate tolerance designs/design2.toml "$patterns/design2_${pattern}.exr" \
    --out "$predicted/tolerance_design2_${pattern}" | tee "$predicted/tolerance_design2_${pattern}.txt"
done

# Designs III and IV (thesis 8.3): figure 8.13's letters, one per incident bin, encoded for
# Design III at the printer's resolution and predicted under a light in the bin of "0" and
# in that of "7" (the field's frame), with the angular distribution a screen in front of
# the display would show (figure 8.13's projected letter) and the 6 x 5 meso-pixels seen
# head-on and from 8 degrees to the right. Figure 8.15's diamonds for Design IV at 150 dpi
# (a preview printer profile written here keeps the 238 mm pattern to 1400 x 1400 dots),
# lit from below and from the left (lights at meso-cell centres), seen from an eye 1 m away and from 8 degrees right.
echo "== predicted display output: Designs III and IV" >&2
"$rfd" pattern encode-angular designs/design3.toml --procedural letters --out "$predicted/design3_letters.exr" \
  | tee "$predicted/design3_letters.txt"
for case in "bin0:--light 15.5,43.8" "bin7:--light 8.7,38.7"; do
  name="${case%%:*}"
  # shellcheck disable=SC2086
  "$rfd" simulate designs/design3.toml "$predicted/design3_letters.exr" ${case#*:} --view 0,0 --view 8,0 --zoom 16 \
    --out "$predicted/design3_${name}.png" --distribution 0,0 --distribution-out "$predicted/design3_${name}_screen.png" \
    --distribution-pixels 128 | tee "$predicted/design3_${name}.txt"
done
sed -e 's/^dpi_x = .*/dpi_x = 150/' -e 's/^dpi_y = .*/dpi_y = 150/' -e 's/^name = "generic 720 dpi inkjet"/name = "150 dpi preview"/' \
  printers/inkjet_720.toml > "$predicted/preview_150dpi.toml"
"$rfd" pattern encode-angular designs/design4.toml --procedural diamonds --dpi 150 --table 65 \
  --out "$predicted/design4_diamonds.exr" | tee "$predicted/design4_diamonds.txt"
for case in "below:--light 8.5,285.5" "side:--light 6.8,180"; do
  name="${case%%:*}"
  # shellcheck disable=SC2086
  "$rfd" simulate designs/design4.toml "$predicted/design4_diamonds.exr" ${case#*:} --printer "$predicted/preview_150dpi.toml" \
    --eye 0,0,1000 --view 8,0 --zoom 8 --out "$predicted/design4_${name}.png" --macro "$predicted/design4_${name}_macro.png" \
    | tee "$predicted/design4_${name}.txt"
done

# The predictions against the software relighting of the same field, at the display's
# resolution (issue 5): PSNR per light direction over a sweep of each display's range (the
# first on the axis, field 45,90 with the tilt) plus the off-axis light above, side-by-side
# pictures and error maps, and the simulator's speed-versus-accuracy chart (paraxial and
# exact against exact with many rays, inside the field of view). Design I's 4599 lenslets
# take 8 rays per side (the default for whole cells: within a dB of 16) and a 16-ray
# reference. About 30 s on 2 cores.
echo "== predicted against relit" >&2
"$rfd" simulate compare designs/design2.toml "$patterns/design2_bottle.exr" "$patterns/bottle_field" --sweep 9 \
  --light 45,70 --chart-accuracy --out "$predicted/compare_design2" | tee "$predicted/compare_design2.txt"
"$rfd" simulate compare designs/design1.toml "$patterns/design1_bottle.exr" "$patterns/bottle_field" --sweep 5 \
  --light 45,70 --chart-accuracy --models paraxial,exact --accuracy-rays 2,4,8 --reference-rays 16 \
  --out "$predicted/compare_design1" | tee "$predicted/compare_design1.txt"

# The lens holders (issue 6): parametric OpenSCAD for the default design (Design I, the
# bottle display) and for Design II (the housing of figure 8.9), each built to STLs with
# openscad and checked (solid, volume, seats at their planes, no ray of the field of view
# touching the holder); and the fit-test coupon that calibrates the clearance. About 30 s.
echo "== lens holders" >&2
holders="$out/holders"
mkdir -p "$holders"
for n in 1 2; do
  "$rfd" holder designs/design$n.toml --printer-profile holders/profiles/fdm_0.4mm.toml \
    --out "$holders/design${n}_holder.scad" --stl "$holders/design${n}_holder.stl" | tee "$holders/design${n}_holder.txt"
done
"$rfd" holder coupon --out "$holders/coupon.scad" --stl "$holders/coupon.stl" | tee "$holders/coupon.txt"

echo "demo written to $out" >&2
