#!/usr/bin/env bash
# make demo: the two bundled projects through rfd make (pattern, print and calibration
# sheets, holder, predictions, verdict, preview page), more predictions of Design I, Designs
# III and IV, then what the design tools say about all four designs. Writes
# OUTPUT_DIR/INDEX.md, a line per file.
# The research reproductions (sampling study, implicit relighting, upsampling) are
# scripts/studies.sh (make studies).
# Usage: scripts/demo.sh RFD_BINARY OUTPUT_DIR
set -euo pipefail
rfd="$1"
out="$2"
source "$(dirname "$0")/index.sh"
index_begin "$out" "rfd demo" \
  "What \`make demo\` wrote, in the order a maker uses it. Paths are relative to this folder."

# The two bundled projects, each made by one command (rfd make): the thesis's SIG08 letters
# on Design II first (its print sheets are ready within a minute of the build), then the
# bottle scene on Design I at the Epson's 2880 x 1440 dpi. Each folder holds README.txt
# (what to print, in which order, how to assemble), index.html (the verdict, a light
# control over the predicted display, the holder in 3D), and every step's command and report.
for project in sig08_design2 bottle_design1; do
  index_section "$project" "rfd make examples/$project.toml"
  "$rfd" make "examples/$project.toml" --out "$out/$project" > "$out/$project.txt"
  index_entry "$project/index.html" "open it in a browser: the verdict, the light control (drag the point: the field relit, the predicted display and their difference), the holder in 3D, and links to every file ($project.txt: what rfd make did)"
  index_entry "$project/README.txt" "what to send to which printer, in which order, and how to assemble; each step's command"
  index_entry "$project/print/front.pdf" "the front sheet: print it on transparency film at 100 %, no scaling (back.pdf: the mirrored back sheet laid behind it, ink to ink)"
  index_entry "$project/print/moire.pdf" "pitch calibration: lay the lens array on it; the band without moire has its true pitch"
  index_entry "$project/print/wedge.pdf" "the step wedge: measure it to fit your printer profile's tone curve"
  index_entry "$project/holder/holder_base.stl" "the holder to 3D-print, base and lid (holder_lid.stl); logs/holder.txt lists the seats and checks"
  index_entry "$project/predict/compare/psnr.png" "how faithfully the display shows the field, PSNR against the light's angle"
  index_entry "$project/predict/tolerance/summary.txt" "how precisely to assemble it"
done
index_entry bottle_design1/print/front.tif "Design I's front sheet also as a TIFF at the printer's true resolution"

# What the bottle displays show beside the field relit in software (lights in the field's
# frame, --frame field): on the display's axis (field theta 45, phi 90, with the 45-degree
# tilt) and 7 degrees off it.
field="$out/bottle_design1/field"
pattern1="$out/bottle_design1/pattern_optimized.exr"  # what the sheets print
index_section predicted "The predicted display"
mkdir -p "$out/predicted"
for case in "axis:--light 45,90" "side:--light 45,80"; do
  name="${case%%:*}"
  # shellcheck disable=SC2086 # the light is two words on purpose
  "$rfd" simulate designs/design1.toml "$pattern1" --frame field ${case#*:} \
    --out "$out/predicted/design1_${name}.png" > "$out/predicted/design1_${name}.txt"
  # shellcheck disable=SC2086
  "$rfd" relight render "$field" ${case#*:} --out "$out/predicted/field_${name}.png" > /dev/null
done
index_entry predicted/design1_axis.png "what Design I will show with a lamp on its axis behind it (field_axis.png: the field relit in software, for comparison)"
index_entry predicted/design1_side.png "Design I with the lamp 7 degrees to the side (field_side.png beside it)"

# More predictions: coloured, disc and environment light; Design I against the field, with
# the speed-versus-accuracy chart of its models.
index_section more_predictions "More predictions"
# A fixed DateTime: oiiotool stamps the time of writing otherwise, and reruns would differ.
oiiotool --nosoftwareattrib --pattern constant:color=4,3.6,3.2 10x6 3 --pattern constant:color=0.04,0.05,0.07 64x32 3 \
  --paste +43+5 -d float --attrib DateTime "2026:01:01 00:00:00" -o "$out/predicted/window_room.exr"
for case in "red_green:--light 45,75,1:0:0 --light 45,105,0:1:0" "disc:--light 45,90,8 --area-samples 3"; do
  name="${case%%:*}"
  # shellcheck disable=SC2086
  "$rfd" simulate designs/design1.toml "$pattern1" --frame field ${case#*:} \
    --out "$out/predicted/design1_${name}.png" > "$out/predicted/design1_${name}.txt"
done
"$rfd" simulate designs/design1.toml "$pattern1" --envmap "$out/predicted/window_room.exr" \
  --out "$out/predicted/design1_window_room.png" > "$out/predicted/design1_window_room.txt"
"$rfd" simulate compare designs/design1.toml "$pattern1" "$field" --sweep 5 \
  --light 45,70 --frame field --chart-accuracy --models paraxial,exact --accuracy-rays 2,4,8 --reference-rays 16 \
  --out "$out/predicted/compare_design1" > "$out/predicted/compare_design1.txt"
index_entry predicted/design1_red_green.png "Design I under a red and a green lamp at once"
index_entry predicted/design1_disc.png "Design I under an 8-degree disc lamp"
index_entry predicted/design1_window_room.png "Design I in a dim room with a bright window behind it (window_room.exr, the environment map)"
index_entry predicted/compare_design1/accuracy.png "when to trust the fast paraxial model and how many rays the simulator needs: speed against accuracy, measured in the same run"

# Designs III and IV (thesis 8.3), as `rfd design tune` spaced them (designs/design3_tuned.toml,
# design4_tuned.toml: 82.9 % of the light on the axis instead of 43.1 %; docs/results.md):
# figure 8.13's letters, one per incident bin, for Design III, seen head-on and from 8 degrees
# to the right with the projected letter a screen in front would show; figure 8.15's diamonds
# for Design IV at 150 dpi (a preview printer profile keeps its 238 mm pattern small), seen
# from an eye 1 m away.
index_section observer_variant "Designs III and IV"
"$rfd" pattern encode-angular designs/design3_tuned.toml --procedural letters --out "$out/predicted/design3_letters.exr" \
  > "$out/predicted/design3_letters.txt"
for case in "bin0:--light 15.5,43.8" "bin7:--light 8.7,38.7"; do
  name="${case%%:*}"
  # shellcheck disable=SC2086
  "$rfd" simulate designs/design3_tuned.toml "$out/predicted/design3_letters.exr" ${case#*:} --view 0,0 --view 8,0 \
    --zoom 16 --out "$out/predicted/design3_${name}.png" --distribution 0,0 \
    --distribution-out "$out/predicted/design3_${name}_screen.png" --distribution-pixels 128 \
    > "$out/predicted/design3_${name}.txt"
done
sed -e 's/^dpi_x = .*/dpi_x = 150/' -e 's/^dpi_y = .*/dpi_y = 150/' \
  -e 's/^name = "generic 720 dpi inkjet"/name = "150 dpi preview"/' printers/inkjet_720.toml \
  > "$out/predicted/preview_150dpi.toml"
"$rfd" pattern encode-angular designs/design4_tuned.toml --procedural diamonds --dpi 150 --table 65 \
  --out "$out/predicted/design4_diamonds.exr" > "$out/predicted/design4_diamonds.txt"
for case in "below:--light 8.5,285.5" "side:--light 6.8,180"; do
  name="${case%%:*}"
  # shellcheck disable=SC2086
  "$rfd" simulate designs/design4_tuned.toml "$out/predicted/design4_diamonds.exr" ${case#*:} \
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
