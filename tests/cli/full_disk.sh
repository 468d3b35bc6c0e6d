#!/usr/bin/env bash
# Every writer, when the disk takes no more: exit 3 (I/O), a message naming the file, and
# nothing at the destination, no temporary left. The disk is "full" by design: a file-size
# limit of a few KB with SIGXFSZ ignored makes every write past it fail (EFBIG), as a full
# disk's do (ENOSPC).
# Usage: full_disk.sh RFD SOURCE_DIR WORK_DIR
set -u
# Under the sanitizers, no leak check at exit: LeakSanitizer's tracer crashes (SIGSEGV) in
# some of these runs on the CI machine, and leaks are what the other tests look for.
export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"
rfd="$1"
source_dir="$2"
work="$3"
rm -rf "$work"
mkdir -p "$work"
designs="$source_dir/designs"
# Inputs, written without a limit.
"$rfd" --quiet capture render "$source_dir/scenes/spheres.toml" --lights 4 --resolution 160x120 \
  --samples-per-pixel 1 --out "$work/field" > /dev/null || exit 1
"$rfd" --quiet pattern field letters --out "$work/letters" > /dev/null || exit 1
"$rfd" --quiet pattern encode "$designs/design2.toml" "$work/letters" --out "$work/pattern.exr" > /dev/null || exit 1

status=0
# check NAME OUTPUT LIMIT_KB COMMAND...: COMMAND, writing OUTPUT into an empty $work/out
# under a LIMIT_KB file-size limit, must fail with exit 3 naming OUTPUT and leave no file in
# $work/out.
check() {
  local name="$1" output="$2" limit="$3"
  shift 3
  rm -rf "$work/out"
  mkdir "$work/out"
  local message
  message=$(trap '' XFSZ; ulimit -f "$limit"; "$rfd" --quiet "$@" 2>&1 > /dev/null)
  local code=$?
  if [ "$code" -ne 3 ]; then
    echo "$name: exit $code, expected 3: $message" >&2
    status=1
  fi
  if ! grep -qF "$output" <<< "$message"; then
    echo "$name: the message does not name $output: $message" >&2
    status=1
  fi
  if [ -n "$(find "$work/out" -type f)" ]; then
    echo "$name: left behind:" >&2
    find "$work/out" -type f >&2
    status=1
  fi
}
check "PNG image" "out/r.png" 8 relight render "$work/field" --light 30,0 --out "$work/out/r.png"
check "EXR image" "out/r.exr" 8 relight render "$work/field" --light 30,0 --out "$work/out/r.exr"
check "HDR image" "out/r.hdr" 8 relight render "$work/field" --light 30,0 --out "$work/out/r.hdr"
check "EXR pattern" "out/p.exr" 8 pattern encode "$designs/design2.toml" "$work/letters" --dpi 720x720 --out "$work/out/p.exr"
check "TIFF pattern" "out/p.tif" 8 pattern encode "$designs/design2.toml" "$work/letters" --dpi 720x720 --out "$work/out/p.tif"
check "TIFF sheet" "out/s.tif" 8 print sheet "$designs/design2.toml" "$work/pattern.exr" --out "$work/out/s.tif"
check "PDF sheet" "out/s.pdf" 8 print sheet "$designs/design2.toml" "$work/pattern.exr" --out "$work/out/s.pdf"
check "moire PDF" "out/m.pdf" 16 print moire "$designs/design2.toml" --pitch 3.9:4.1:30 --out "$work/out/m.pdf"
check "OpenSCAD holder" "out/h.scad" 8 holder "$designs/design3.toml" --out "$work/out/h.scad"
check "field image" "out/f/field_0000.exr" 8 capture render "$source_dir/scenes/spheres.toml" --lights 4 \
  --resolution 160x120 --samples-per-pixel 1 --out "$work/out/f"
# The disk full at the very end, when the writer's last buffered bytes go out on closing.
for ext in png exr hdr tif; do
  "$rfd" --quiet relight render "$work/field" --light 30,0 --out "$work/whole.$ext" > /dev/null || exit 1
  size=$(stat -c %s "$work/whole.$ext")
  check "$ext image cut in its last KB" "out/r.$ext" $(((size - 1) / 1024)) \
    relight render "$work/field" --light 30,0 --out "$work/out/r.$ext"
done

# A chart: gnuplot does not report a failed write, it cuts the file short. The CSVs and
# gnuplot scripts before it are whole files; the picture cut short must not be there.
rm -rf "$work/out"
mkdir "$work/out"
message=$(trap '' XFSZ; ulimit -f 8; "$rfd" --quiet optics chart "$designs/design2.toml" --out "$work/out/chart" 2>&1 > /dev/null)
code=$?
if [ "$code" -ne 3 ] || ! grep -q "paraxial_error_x.svg: gnuplot wrote it cut short" <<< "$message"; then
  echo "chart: exit $code, expected 3 naming the picture: $message" >&2
  status=1
fi
if [ -n "$(find "$work/out" -name '*.svg' -o -name '*.png' -o -name '.tmp*')" ]; then
  echo "chart: pictures or temporaries left behind:" >&2
  ls -A "$work/out/chart" >&2
  status=1
fi
exit "$status"
