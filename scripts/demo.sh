#!/usr/bin/env bash
# make demo: from the bundled bottle scene to what a maker prints, builds and checks for
# Designs I and II (patterns, print sheets, lens holders, the predicted display), then what
# the design tools say about all four designs. Writes OUTPUT_DIR/INDEX.md, a line per file.
# The research reproductions (sampling study, implicit relighting, upsampling) are
# scripts/studies.sh (make studies).
# Usage: scripts/demo.sh RFD_BINARY OUTPUT_DIR
set -euo pipefail
rfd="$1"
out="$2"
source "$(dirname "$0")/index.sh"
index_begin "$out" "rfd demo" \
  "What \`make demo\` wrote, in the order a maker uses it. Paths are relative to this folder."

index_section field "The source field"
"$rfd" capture render scenes/bottle.toml --lights 400 --resolution 128x64 --out "$out/field" > "$out/field.txt"
index_entry field/field.lp "the bottle scene (scenes/bottle.toml) rendered under 400 light directions, 128 x 64: the reflectance field every display below shows (field.txt: how it was rendered)"

# Patterns (thesis 8.4): the field encoded for Designs I and II at the thesis's printer
# resolution, 2880 x 1440 dpi, with the light tilted by 45 degrees as the thesis did; and
# the "SIG08" letters of its Design II demonstration.
index_section patterns "Patterns"
mkdir -p "$out/patterns"
for n in 1 2; do
  "$rfd" pattern encode "designs/design$n.toml" "$out/field" --tilt 45 \
    --out "$out/patterns/design${n}_bottle.exr" --preview "$out/patterns/design${n}_bottle.png" \
    > "$out/patterns/design${n}_bottle.txt"
done
"$rfd" pattern field letters --text SIG08 --resolution 48x40 --out "$out/patterns/sig08_field" > /dev/null
"$rfd" pattern encode designs/design2.toml "$out/patterns/sig08_field" --interpolation nearest \
  --out "$out/patterns/design2_sig08.exr" --preview "$out/patterns/design2_sig08.png" > "$out/patterns/design2_sig08.txt"
index_entry patterns/design1_bottle.png "Design I's pattern of the bottle, scaled down for the screen (the full pattern is the .exr beside it, 2880 x 1440 dpi; .txt: the encoder's summary)"
index_entry patterns/design2_bottle.png "Design II's pattern of the bottle"
index_entry patterns/design2_sig08.png "Design II's pattern of the SIG08 letters, a test field: each letter shows under its own light"

# Print sheets (thesis 8.4, 8.4.1): front and mirrored back sheets for back-to-back
# printing, registration markers under the corner lenslets, crop marks, ruler and label.
index_section sheets "Print sheets"
mkdir -p "$out/sheets"
for side in front back; do
  mirror=()
  if [ "$side" = back ]; then mirror=(--mirror); fi
  "$rfd" print sheet designs/design1.toml "$out/patterns/design1_bottle.exr" --printer epson_stylus_pro_4800 \
    "${mirror[@]}" --out "$out/sheets/design1_bottle_$side.tif" > "$out/sheets/design1_bottle_$side.txt"
  for name in design2_bottle design2_sig08; do
    "$rfd" print sheet designs/design2.toml "$out/patterns/$name.exr" "${mirror[@]}" \
      --out "$out/sheets/${name}_$side.pdf" > "$out/sheets/${name}_$side.txt"
  done
done
"$rfd" print moire designs/design1.toml --pitch 2.350:2.366:9 --out "$out/sheets/design1_moire.pdf" \
  > "$out/sheets/design1_moire.txt"
index_entry sheets/design1_bottle_front.tif "Design I's front sheet, A4 at the Epson Stylus Pro 4800's true 2880 x 1440 dpi: print it on transparency film at that resolution, no scaling"
index_entry sheets/design1_bottle_back.tif "Design I's mirrored back sheet: print it too and lay it behind the front one, ink to ink, markers on markers (two sheets double the density)"
index_entry sheets/design2_bottle_front.pdf "Design II's front sheet as PDF (and design2_bottle_back.pdf, mirrored)"
index_entry sheets/design2_sig08_front.pdf "the SIG08 letters for Design II (and design2_sig08_back.pdf)"
index_entry sheets/design1_moire.pdf "pitch calibration: print it, lay the lens array on it, and use the band without moire (its pitch goes into the design's lattice)"

# The lens holders (thesis 8.2.4): parametric OpenSCAD for Designs I and II, built to STLs
# and checked (solid, volume, seats at their planes, no ray of the field of view touching
# the holder), and the fit-test coupon that calibrates the clearance.
index_section holders "Lens holders"
mkdir -p "$out/holders"
for n in 1 2; do
  "$rfd" holder designs/design$n.toml --3d-printer holders/profiles/fdm_0.4mm.toml \
    --out "$out/holders/design${n}_holder.scad" --stl "$out/holders/design${n}_holder.stl" \
    > "$out/holders/design${n}_holder.txt"
done
"$rfd" holder coupon --out "$out/holders/coupon.scad" --stl "$out/holders/coupon.stl" > "$out/holders/coupon.txt"
index_entry holders/coupon.stl "print this first: nine seats per row step the clearance by 0.05 mm; the one that takes your lens with a slip fit goes into clearance_mm of your printer profile"
index_entry holders/design1_holder_base.stl "Design I's holder, base and lid (design1_holder_lid.stl), for a 0.4 mm FDM nozzle; design1_holder.txt lists the seats and the checks passed; the .scad is the OpenSCAD source"
index_entry holders/design2_holder_base.stl "Design II's housing with its baffles, base and lid"

# What the displays will show (thesis 8.2), beside the same lights relighting the field in
# software (so named in the field's frame, --frame field): on the display's axis (field
# theta 45, phi 90, with the 45-degree tilt) and 7 degrees off it, inside both designs'
# crosstalk-free cones.
index_section predicted "The predicted display"
mkdir -p "$out/predicted"
for case in "axis:--light 45,90" "side:--light 45,80"; do
  name="${case%%:*}"
  for n in 1 2; do
    # shellcheck disable=SC2086 # the light is two words on purpose
    "$rfd" simulate "designs/design$n.toml" "$out/patterns/design${n}_bottle.exr" --frame field ${case#*:} \
      --out "$out/predicted/design${n}_${name}.png" > "$out/predicted/design${n}_${name}.txt"
  done
  # shellcheck disable=SC2086
  "$rfd" relight render "$out/field" ${case#*:} --out "$out/predicted/field_${name}.png" > /dev/null
done
"$rfd" simulate compare designs/design2.toml "$out/patterns/design2_bottle.exr" "$out/field" --sweep 9 \
  --light 45,70 --chart-accuracy --out "$out/predicted/compare_design2" > "$out/predicted/compare_design2.txt"
"$rfd" simulate tolerance designs/design2.toml "$out/patterns/design2_sig08.exr" \
  --out "$out/predicted/tolerance_design2_sig08" > "$out/predicted/tolerance_design2_sig08.txt"
index_entry predicted/design1_axis.png "what Design I will show with a lamp on its axis behind it (field_axis.png: the field relit in software, for comparison)"
index_entry predicted/design1_side.png "Design I with the lamp 7 degrees to the side (field_side.png beside it)"
index_entry predicted/design2_axis.png "Design II, lamp on the axis (and design2_side.png)"
index_entry predicted/compare_design2/psnr.png "how faithfully Design II shows the field, PSNR against the light's angle (summary in compare_design2.txt, pictures per light in the folder)"
index_entry predicted/tolerance_design2_sig08.txt "how precisely to assemble Design II: the shift, rotation, pitch and spacer errors it tolerates (charts in the folder)"

# More predictions: coloured, disc and environment light; Design I against the field.
index_section more_predictions "More predictions"
# A fixed DateTime: oiiotool stamps the time of writing otherwise, and reruns would differ.
oiiotool --nosoftwareattrib --pattern constant:color=4,3.6,3.2 10x6 3 --pattern constant:color=0.04,0.05,0.07 64x32 3 \
  --paste +43+5 -d float --attrib DateTime "2026:01:01 00:00:00" -o "$out/predicted/window_room.exr"
for n in 1 2; do
  for case in "red_green:--light 45,75,1:0:0 --light 45,105,0:1:0" "disc:--light 45,90,8 --area-samples 3"; do
    name="${case%%:*}"
    # shellcheck disable=SC2086
    "$rfd" simulate "designs/design$n.toml" "$out/patterns/design${n}_bottle.exr" --frame field ${case#*:} \
      --out "$out/predicted/design${n}_${name}.png" > "$out/predicted/design${n}_${name}.txt"
  done
  "$rfd" simulate "designs/design$n.toml" "$out/patterns/design${n}_bottle.exr" --envmap "$out/predicted/window_room.exr" \
    --out "$out/predicted/design${n}_window_room.png" > "$out/predicted/design${n}_window_room.txt"
done
"$rfd" simulate compare designs/design1.toml "$out/patterns/design1_bottle.exr" "$out/field" --sweep 5 \
  --light 45,70 --chart-accuracy --models paraxial,exact --accuracy-rays 2,4,8 --reference-rays 16 \
  --out "$out/predicted/compare_design1" > "$out/predicted/compare_design1.txt"
"$rfd" simulate tolerance designs/design2.toml "$out/patterns/design2_bottle.exr" \
  --out "$out/predicted/tolerance_design2_bottle" > "$out/predicted/tolerance_design2_bottle.txt"
index_entry predicted/design1_red_green.png "Design I under a red and a green lamp at once (design2_red_green.png too)"
index_entry predicted/design1_disc.png "Design I under an 8-degree disc lamp (design2_disc.png too)"
index_entry predicted/design1_window_room.png "Design I in a dim room with a bright window behind it (window_room.exr, the environment map)"
index_entry predicted/compare_design1/psnr.png "Design I against the field, as compare_design2"
index_entry predicted/tolerance_design2_bottle.txt "Design II's assembly tolerances for the smooth bottle pattern (the letters are less forgiving)"

# Designs III and IV (thesis 8.3): figure 8.13's letters, one per incident bin, for Design
# III, seen head-on and from 8 degrees to the right with the projected letter a screen in
# front would show; figure 8.15's diamonds for Design IV at 150 dpi (a preview printer
# profile keeps its 238 mm pattern small), seen from an eye 1 m away.
index_section observer_variant "Designs III and IV"
"$rfd" pattern encode-angular designs/design3.toml --procedural letters --out "$out/predicted/design3_letters.exr" \
  > "$out/predicted/design3_letters.txt"
for case in "bin0:--light 15.5,43.8" "bin7:--light 8.7,38.7"; do
  name="${case%%:*}"
  # shellcheck disable=SC2086
  "$rfd" simulate designs/design3.toml "$out/predicted/design3_letters.exr" ${case#*:} --view 0,0 --view 8,0 \
    --zoom 16 --out "$out/predicted/design3_${name}.png" --distribution 0,0 \
    --distribution-out "$out/predicted/design3_${name}_screen.png" --distribution-pixels 128 \
    > "$out/predicted/design3_${name}.txt"
done
sed -e 's/^dpi_x = .*/dpi_x = 150/' -e 's/^dpi_y = .*/dpi_y = 150/' \
  -e 's/^name = "generic 720 dpi inkjet"/name = "150 dpi preview"/' printers/inkjet_720.toml \
  > "$out/predicted/preview_150dpi.toml"
"$rfd" pattern encode-angular designs/design4.toml --procedural diamonds --dpi 150 --table 65 \
  --out "$out/predicted/design4_diamonds.exr" > "$out/predicted/design4_diamonds.txt"
for case in "below:--light 8.5,285.5" "side:--light 6.8,180"; do
  name="${case%%:*}"
  # shellcheck disable=SC2086
  "$rfd" simulate designs/design4.toml "$out/predicted/design4_diamonds.exr" ${case#*:} \
    --printer "$out/predicted/preview_150dpi.toml" --eye 0,0,1000 --view 8,0 --zoom 8 \
    --out "$out/predicted/design4_${name}.png" --macro "$out/predicted/design4_${name}_macro.png" \
    > "$out/predicted/design4_${name}.txt"
done
index_entry predicted/design3_bin0_screen_0_0.png "Design III lit in the bin of the letter 0: the letter a screen in front of it shows (figure 8.13); design3_bin0_view1.png and _view2.png are its meso-pixels seen head-on and from 8 degrees"
index_entry predicted/design3_bin7_screen_0_0.png "the same, lit in the bin of the letter 7"
index_entry predicted/design4_below_view1.png "Design IV's diamonds lit from below, seen by an eye 1 m away (design4_below_macro_view1.png: one value per macro-pixel)"

# The design tools: for each of Designs I-IV the system summary and the speed-versus-
# accuracy chart of the paraxial model against the exact tracer; the bundled lenses.
index_section designs "Designs I-IV"
for n in 1 2 3 4; do
  dir="$out/designs/design$n"
  mkdir -p "$dir"
  "$rfd" design show "designs/design$n.toml" > "$dir/summary.txt"
  "$rfd" design show "designs/design$n.toml" --json > "$dir/summary.json"
  "$rfd" optics chart "designs/design$n.toml" --out "$dir/chart" > "$dir/chart.txt"
done
mkdir -p "$out/designs/lenses"
for lens in designs/lenses/*.toml; do
  name="$(basename "$lens" .toml)"
  "$rfd" optics system "$lens" > "$out/designs/lenses/$name.txt"
  "$rfd" optics trace "$lens" --angle 5 >> "$out/designs/lenses/$name.txt"
done
index_entry designs/design1/summary.txt "Design I's summary: lenslet pitch, print dots per lenslet, wrap-over angle, field of view, light efficiency, focus checks and design-rule warnings (summary.json: the same for programs; design2..4 alike)"
index_entry designs/design1/chart/paraxial_error_x.png "when to trust the fast paraxial model: its error on the pattern plane against the exact trace, by angle along x (_y: along y)"
index_entry designs/lenses/edmund_pcx_25x50.txt "a bundled lens: focal lengths, principal planes, and an exact trace at 5 degrees"

index_end
