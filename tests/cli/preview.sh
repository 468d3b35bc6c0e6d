#!/usr/bin/env bash
# The preview page in a browser: headless Chromium opens index.html of an `rfd make` output
# (through tests/preview/harness.html), moves the light with the page's own control, and
# the picture the page shows is compared with `rfd simulate` at the light the page reports:
#  - dragged onto a precomputed direction: equal up to 8-bit rounding (max 2/255);
#  - dragged between directions, then moved with arrow keys: the blend of its neighbours,
#    within the interpolation error on this smooth field (PSNR >= 40 dB against simulate;
#    51.7 dB measured);
#  - switched to the direct encoding the pattern was optimised from: equal to rfd simulate
#    of the direct pattern on a precomputed direction, as above;
#  - no console message and no uncaught error from the page.
# Usage: preview.sh RFD CHROMIUM OIIOTOOL SOURCE_DIR WORK_DIR
set -euo pipefail
rfd="$1"
chromium="$2"
oiiotool="$3"
source_dir="$4"
work="$5"
rm -rf "$work"
mkdir -p "$work"
fail() {
  echo "FAIL: $1" >&2
  exit 1
}

# A smooth field (the spheres under 60 lights) on Design II, with nothing but the pattern
# (optimised, briefly) and the preview made.
"$rfd" --quiet capture render "$source_dir/scenes/spheres.toml" --lights 60 --resolution 48x36 \
  --out "$work/field" > /dev/null
cat > "$work/project.toml" <<TOML
[project]
design = "design2"
printer = "inkjet_720"
[source]
field = "field"
[make]
sheets = []
moire = false
wedge = false
holder = false
compare_sweep = 0
tolerance = false
preview_lights = 48
[optimize]
iterations = 4
spacing_mm = 0.25
TOML
"$rfd" make "$work/project.toml" --out "$work/out" > "$work/make.txt"

# open QUERY NAME: runs the harness, leaves NAME.json (the result) and NAME_page.png.
open_page() {
  "$chromium" --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader --allow-file-access-from-files \
    --enable-logging=stderr --v=0 --virtual-time-budget=30000 --dump-dom \
    "file://$source_dir/tests/preview/harness.html?page=file://$work/out/index.html&$1" \
    > "$work/$2.dom" 2> "$work/$2.log" || fail "chromium failed: $(tail -5 "$work/$2.log")"
  grep -o 'RESULT .* END' "$work/$2.dom" | sed -e 's/^RESULT //' -e 's/ END$//' > "$work/$2.json" \
    || fail "the page did not report (is it ready?): $(tail -c 600 "$work/$2.dom")"
  if grep -E 'CONSOLE|Uncaught' "$work/$2.log" | grep -v 'harness.html' > "$work/$2.console"; then
    fail "the page wrote to the console: $(cat "$work/$2.console")"
  fi
  sed -e 's/.*"png":"data:image\/png;base64,//' -e 's/".*//' "$work/$2.json" | base64 -d > "$work/$2_page.png"
}
value() { sed -e "s/.*\"$1\":\([-0-9.e]*\).*/\1/" "$work/$2.json"; }

# simulate NAME: rfd simulate at the light the page reports, at the page's scale.
simulate() {
  local theta phi stops pattern="${2:-pattern_optimized.exr}"
  theta=$(value theta "$1")
  phi=$(value phi "$1")
  stops=$(awk -v s="$(value scale "$1")" 'BEGIN { printf "%.10f", log(s) / log(2) }')
  "$rfd" --quiet simulate designs/design2.toml "$work/out/$pattern" --light "$theta,$phi" --exposure "$stops" \
    --lenslets "$work/$1_simulate.png" --out "$work/$1_diffuser.exr" > /dev/null
}

cd "$source_dir"
open_page "target=7" onto
simulate onto
"$oiiotool" "$work/onto_page.png" --ch R,G,B "$work/onto_simulate.png" --diff --fail 0.0079 --failpercent 0 > "$work/onto.diff" \
  || fail "on a precomputed direction the page differs from rfd simulate: $(cat "$work/onto.diff")"

open_page "target=7&pattern=direct" direct
grep -q '"pattern":"direct"' "$work/direct.json" || fail "the page did not switch to the direct encoding"
simulate direct pattern.exr
"$oiiotool" "$work/direct_page.png" --ch R,G,B "$work/direct_simulate.png" --diff --fail 0.0079 --failpercent 0 > "$work/direct.diff" \
  || fail "switched to the direct encoding the page differs from rfd simulate of it: $(cat "$work/direct.diff")"
"$oiiotool" "$work/direct_page.png" "$work/onto_page.png" --diff > "$work/switch.diff" \
  && fail "the direct encoding and the optimised pattern show the same picture"

open_page "drag=0.45,0.3&keys=3" between
simulate between
"$oiiotool" "$work/between_page.png" --ch R,G,B "$work/between_simulate.png" --diff > "$work/between.diff" || true
psnr=$(sed -n 's/.*Peak SNR = \([0-9.inf]*\).*/\1/p' "$work/between.diff")
awk -v p="$psnr" 'BEGIN { exit !(p == "inf" || p >= 40) }' \
  || fail "between directions the page is $psnr dB from rfd simulate (< 40): $(cat "$work/between.diff")"
grep -q "from the display's axis" "$work/between.json" || fail "the page does not report the light"
echo "preview: onto a direction equal to rfd simulate;" \
  "between, $(value theta between),$(value phi between) deg: $psnr dB; loaded in $(value loaded_ms between) ms"
