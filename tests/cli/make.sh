#!/usr/bin/env bash
# `rfd make` end to end, as a user runs it:
#  1. a project on a field folder: everything made, a second run makes nothing, a changed
#     field re-makes only what reads it (not the moire sheet), and the pattern records the
#     project's printer;
#  2. an RTIBuilder-style capture (absolute Windows paths, CRLF, JPEGs in jpeg-exports/, a
#     bright "sphere" in a corner outside the object) made through a `region`, no edits;
#  3. a project that names an unknown key: exit 2, the file and line, nothing made;
#  4. the same project into a deeper folder with -j 1 gives the same bytes as -j 2 (logs aside);
#     a command of README.txt run from a copy of the folder re-makes its file as it was;
#     --only makes the named step and what it reads;
#  5. SIGTERM while a step runs: exit 143, the step's process ended, no temporary or
#     half-written file, and the next make finishes the rest; a second make into a folder
#     another one is making into is refused;
#  6. sources that are not regular files (a device, a folder as scene) are refused at once.
# Usage: make.sh RFD OIIOTOOL SOURCE_DIR WORK_DIR
set -euo pipefail
rfd="$1"
oiiotool="$2"
source_dir="$3"
work="$4"
rm -rf "$work"
mkdir -p "$work"
fail() {
  echo "FAIL: $1" >&2
  exit 1
}
expect_line() {  # expect_line FILE STEP STATE
  grep -Eq "\] $2 +$3" "$1" || fail "step $2 was not '$3': $(cat "$1")"
}

"$rfd" --quiet pattern field letters --text SIG08 --resolution 24x20 --out "$work/field" > /dev/null
# A coarse printer on A5, so the sheets stay small.
cat > "$work/a5_printer.toml" <<TOML
[printer]
name = "coarse A5 test printer"
dpi_x = 360
dpi_y = 360
gamma = 2.2
max_density = 2.0
black_level = 0.012
sheets = 1

[paper]
name = "A5"
width_mm = 148
height_mm = 210
margin_mm = 3
TOML
cat > "$work/letters.toml" <<TOML
[project]
name = "letters on a test card"
design = "design2"
printer = "a5_printer.toml"

[source]
field = "field"

[encode]
interpolation = "nearest"

[make]
sheets = ["pdf", "tif"]
holder = false
compare_sweep = 3

[optimize]
iterations = 4   # the step as a maker gets it by default, a few iterations to keep the test short
TOML
"$rfd" make "$work/letters.toml" --out "$work/out" > "$work/run1.txt"
for file in pattern.exr pattern.png print/front.pdf print/front.tif print/moire.pdf predict/compare/psnr.png print/wedge.pdf print/front.png preview/data.js verdict.json \
            predict/tolerance/summary.txt README.txt index.html manifest.json logs/pattern.txt; do
  [ -s "$work/out/$file" ] || fail "run 1 did not write $file"
done
grep -q "11 step(s) made, 0 up to date" "$work/run1.txt" || fail "run 1: $(cat "$work/run1.txt")"
# The advice, said as soon as it is made (before the pattern), and on the page.
grep -A1 "advice  *made" "$work/run1.txt" | grep -q "shows 6 x 5 picture elements" || fail "no advice: $(cat "$work/run1.txt")"
grep -q "^Advice on this field" "$work/out/README.txt" || fail "README.txt lacks the advice"
grep -q 'class="advice"' "$work/out/index.html" || fail "index.html lacks the advice"
grep -q "coarse A5 test printer" "$work/out/logs/pattern.txt" || fail "the pattern does not record the project's printer"
grep -Eq "^verdict: (go|check|no-go): " "$work/run1.txt" || fail "no verdict: $(cat "$work/run1.txt")"
grep -Eq "^  on this field: (go|check|no-go): " "$work/run1.txt" || fail "no verdict on the field: $(cat "$work/run1.txt")"
grep -Eq "^  on the design: check: design warning: " "$work/run1.txt" || fail "Design II's warning is not the design's part"
grep -Eq "^Verdict: (go|check|no-go): " "$work/out/README.txt" || fail "README.txt lacks the verdict"
grep -q 'class="verdict' "$work/out/index.html" || fail "index.html lacks the verdict"
grep -q "rfd print sheet .*pattern_optimized.exr --copies 0 --out print/front.tif" "$work/out/README.txt" || fail "README.txt lacks the commands"

"$rfd" make "$work/letters.toml" --out "$work/out" > "$work/run2.txt"
grep -q "0 step(s) made, 11 up to date" "$work/run2.txt" || fail "run 2 made something: $(cat "$work/run2.txt")"

"$rfd" --quiet pattern field letters --text GRAPH --resolution 24x20 --out "$work/field" > /dev/null
"$rfd" make "$work/letters.toml" --out "$work/out" > "$work/run3.txt"
expect_line "$work/run3.txt" pattern made
expect_line "$work/run3.txt" sheet_front_pdf made
expect_line "$work/run3.txt" compare made
expect_line "$work/run3.txt" moire "up to date"
expect_line "$work/run3.txt" wedge "up to date"

# 2. The capture as RTIBuilder leaves it: spheres.toml rendered, each picture pasted into a
# larger frame with a white calibration "sphere" in its top-left corner, saved as JPEG.
"$rfd" --quiet capture render "$source_dir/scenes/spheres.toml" --lights 40 --resolution 48x36 \
  --out "$work/render" > /dev/null
mkdir -p "$work/capture/jpeg-exports"
printf '40\r\n' > "$work/capture/Bottle.lp"
n=0
while read -r file x y z; do
  n=$((n + 1))
  name=$(printf 'Bottle_%03d.jpg' "$n")
  # --paste puts the image below the top of the stack onto the top one.
  "$oiiotool" "$work/render/$file" --pattern constant:color=0.02,0.02,0.02 72x56 3 --paste +16+12 \
    --pattern constant:color=1,1,1 8x8 3 --swap --paste +2+2 -d uint8 -o "$work/capture/jpeg-exports/$name"
  printf 'C:\\Users\\Maker\\Documents\\Bottle\\jpeg-exports\\%s %s %s %s\r\n' "$name" "$x" "$y" "$z" \
    >> "$work/capture/Bottle.lp"
done < <(tail -n +2 "$work/render/field.lp")
cat > "$work/capture.toml" <<TOML
[project]
design = "design2"
printer = "a5_printer.toml"

[source]
field = "capture/Bottle.lp"
region = [16, 12, 48, 36]

[make]
sheets = ["pdf"]
moire = false
wedge = false
holder = false
compare_sweep = 3
tolerance = false

[encode]
tilt_deg = "auto"

[optimize]
enabled = false
TOML
"$rfd" make "$work/capture.toml" --out "$work/capture_out" > "$work/capture.txt" \
  || fail "the RTIBuilder capture did not go through: $(cat "$work/capture.txt")"
grep -q "region" "$work/out/README.txt" && fail "the letters project should have no region"
grep -q -- "--region 16,12,48,36" "$work/capture_out/README.txt" || fail "the capture's region is not passed on"
grep -q -- "pattern encode .*--tilt auto" "$work/capture_out/README.txt" || fail "tilt_deg = \"auto\" is not passed on"
grep -Eq "tilt -?[0-9]+ deg" "$work/capture_out/logs/pattern.txt" || fail "the pattern does not say the tilt auto chose"

# 3. A mistake in the project file.
printf '[project]\ndesign = "design2"\ncolour = "red"\n[source]\nfield = "field"\n' > "$work/bad.toml"
set +e
"$rfd" make "$work/bad.toml" --out "$work/bad_out" > /dev/null 2> "$work/bad.txt"
code=$?
set -e
[ "$code" = 2 ] || fail "a bad project file exited $code"
grep -q "bad.toml:3:.*project.colour: unknown key" "$work/bad.txt" || fail "message: $(cat "$work/bad.txt")"
[ ! -e "$work/bad_out" ] || fail "a bad project file made something"
# 4. Two folders, one and two steps at a time: the same files, byte for byte.
"$rfd" make "$work/letters.toml" --out "$work/deeper/folder/out" -j 1 > "$work/run_j1.txt"
grep -q "11 step(s) made" "$work/run_j1.txt" || fail "-j 1: $(cat "$work/run_j1.txt")"
diff -r --exclude=logs "$work/out" "$work/deeper/folder/out" > "$work/diff.txt" \
  || fail "-j 1 into another folder differs from -j 2: $(head -5 "$work/diff.txt")"
grep -rq -- "$work/out" "$work/out" --exclude-dir=logs && fail "an output records the output folder's path"
# README.txt's commands run from its folder, wherever it has moved.
cp -r "$work/out" "$work/moved"
sheet_command=$(grep -E '^    rfd print sheet .*front.pdf' "$work/moved/README.txt")
[ -n "$sheet_command" ] || fail "README.txt has no sheet command"
rm "$work/moved/print/front.pdf"
(cd "$work/moved" && PATH="$(dirname "$rfd"):$PATH" && eval "$sheet_command --quiet" > /dev/null) \
  || fail "README.txt's command failed from its folder: $sheet_command"
cmp -s "$work/moved/print/front.pdf" "$work/out/print/front.pdf" || fail "README.txt's command made another sheet"
"$rfd" make "$work/letters.toml" --out "$work/only" --only sheet_front_pdf > "$work/only.txt"
grep -q "3 step(s) made" "$work/only.txt" || fail "--only: $(cat "$work/only.txt")"
[ -s "$work/only/print/front.pdf" ] && [ ! -e "$work/only/print/moire.pdf" ] || fail "--only made the wrong files"

# 5. SIGTERM while a step runs, and a second make meanwhile.
running_step() {  # waits until a step of folder $1 runs; prints its log's name
  for _ in $(seq 1 1500); do
    found=$(find "$1/logs" -name '.running-*' 2>/dev/null | head -1)
    [ -n "$found" ] && { echo "$found"; return 0; }
    sleep 0.01
  done
  return 1
}
"$rfd" make "$work/letters.toml" --out "$work/killed" -j 1 > "$work/killed.txt" 2>&1 &
make_pid=$!
running_step "$work/killed" > /dev/null || fail "no step of the make to stop ever ran"
set +e
"$rfd" make "$work/letters.toml" --out "$work/killed" > /dev/null 2> "$work/second.txt"
second=$?
kill -TERM "$make_pid"
wait "$make_pid"
code=$?
set -e
[ "$second" = 3 ] || fail "a second make into a busy folder exited $second"
grep -q "another rfd make is making into" "$work/second.txt" || fail "second make: $(cat "$work/second.txt")"
[ "$code" = 143 ] || fail "rfd make stopped by SIGTERM exited $code: $(cat "$work/killed.txt")"
for proc in /proc/[0-9]*; do
  [ "$(readlink "$proc/cwd" 2>/dev/null)" = "$work/killed" ] && fail "a step still runs after SIGTERM: $(cat "$proc/cmdline" | tr '\0' ' ')"
done
leftovers=$(find "$work/killed" -name '.tmp*' -o -name '.running-*')
[ -z "$leftovers" ] || fail "SIGTERM left $leftovers"
"$rfd" make "$work/letters.toml" --out "$work/killed" > "$work/killed2.txt" || fail "the make after SIGTERM failed"
diff -r --exclude=logs "$work/out" "$work/killed" > /dev/null || fail "the make after SIGTERM differs"

# 6. Sources that are not regular files: refused at once, naming the key.
printf '[project]\ndesign = "design2"\n[source]\nfield = "/dev/zero"\n' > "$work/device.toml"
printf '[project]\ndesign = "design2"\n[source]\nscene = "field"\n' > "$work/folder.toml"
for project in device folder; do
  set +e
  timeout 20 "$rfd" make "$work/$project.toml" --out "$work/${project}_out" --dry-run > /dev/null 2> "$work/$project.txt"
  code=$?
  set -e
  [ "$code" = 2 ] || fail "a $project as source exited $code: $(cat "$work/$project.txt")"
  grep -q "source\.\(field\|scene\)" "$work/$project.txt" || fail "message: $(cat "$work/$project.txt")"
done

echo "rfd make: all checks passed"
