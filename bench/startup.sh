#!/usr/bin/env bash
# Start-up time and peak memory of rfd commands, beside baselines built and measured in the
# same run: a trivial C++ program linked with exactly the shared libraries rfd links (what
# rfd cannot start faster than), and two with OpenImageIO: one that only loads it, and one
# that does through it the file work of rfd relight render, reading a 4-light 16x12 field and
# writing a PNG (what any program doing that pays; rfd loads OpenImageIO on first use,
# core/module.hpp, and reads and writes common EXR files without it, core/exr_file.hpp). Times from hyperfine (mean of RUNS runs after warm-up), memory from GNU time (peak resident set, the largest of 3 runs).
# Usage: bench/startup.sh [BUILD_DIR] [RUNS]     (make demo or make test builds BUILD_DIR/bin/rfd)
set -euo pipefail
build="${1:-build}"
runs="${2:-20}"
rfd="$(realpath "$build/bin/rfd")"
for tool in hyperfine g++ readelf; do
  command -v "$tool" > /dev/null || { echo "startup.sh: needs $tool (apt-get install hyperfine g++ binutils)" >&2; exit 1; }
done
[ -x /usr/bin/time ] || { echo "startup.sh: needs GNU time (apt-get install time)" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$(dirname "$0")/.."

# Baselines. --no-as-needed keeps every library loaded that main() does not use.
echo 'int main() { return 0; }' > "$work/trivial.cpp"
mapfile -t needed < <(readelf -d "$rfd" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
links=()
for library in "${needed[@]}"; do links+=("-l:$library"); done
g++ -O2 "$work/trivial.cpp" -o "$work/trivial_as_rfd" -Wl,--no-as-needed "${links[@]}"
g++ -O2 "$work/trivial.cpp" -o "$work/trivial_oiio" -Wl,--no-as-needed -lOpenImageIO -lOpenImageIO_Util
# What OpenImageIO alone takes to do rfd relight render's file work: read the field's
# images, write one PNG.
printf '%s\n' '#include <OpenImageIO/imageio.h>' '#include <vector>' \
  'int main(int argc, char** argv) {' \
  '    std::vector<float> pixels;' \
  '    for (int i = 2; i < argc; ++i) {' \
  '        auto in = OIIO::ImageInput::open(argv[i]);' \
  '        if (!in) return 1;' \
  '        pixels.resize(in->spec().image_pixels() * in->spec().nchannels);' \
  '        if (!in->read_image(0, 0, 0, -1, OIIO::TypeDesc::FLOAT, pixels.data())) return 1;' \
  '    }' \
  '    auto out = OIIO::ImageOutput::create(argv[1]);' \
  '    OIIO::ImageSpec spec(16, 12, 3, OIIO::TypeDesc::UINT8);' \
  '    std::vector<unsigned char> bytes(16 * 12 * 3, 128);' \
  '    return out && out->open(argv[1], spec) && out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) && out->close() ? 0 : 1;' \
  '}' > "$work/read_image.cpp"
g++ -O2 -std=c++17 "$work/read_image.cpp" -o "$work/read_image_oiio" -lOpenImageIO -lOpenImageIO_Util

"$rfd" capture render scenes/spheres.toml --lights 4 --resolution 16x12 --samples-per-pixel 1 \
  --out "$work/field" > /dev/null
"$rfd" relight render "$work/field" --light 30,0 --out "$work/relit.png" > /dev/null
field_images=("$work"/field/*.exr)

names=("baseline: trivial, rfd's libraries" "rfd --version" "rfd --help" "rfd design show designs/design1.toml"
       "rfd optics trace (a lens, 5 deg)" "rfd holder designs/design2.toml (.scad)"
       "rfd relight render (16x12 field, to EXR)"
       "baseline: trivial, OpenImageIO" "baseline: OIIO reads 4 EXRs, writes a PNG" "rfd relight render (16x12 field)")
commands=("$work/trivial_as_rfd" "$rfd --version" "$rfd --help" "$rfd design show designs/design1.toml"
          "$rfd optics trace designs/lenses/edmund_pcx_25x50.toml --angle 5"
          "$rfd holder designs/design2.toml --out $work/holder.scad"
          "$rfd relight render $work/field --light 30,0 --out $work/relit.exr"
          "$work/trivial_oiio" "$work/read_image_oiio $work/copy.png ${field_images[*]}"
          "$rfd relight render $work/field --light 30,0 --out $work/relit.png")

# Each command's time also as a ratio to the baseline listed last above it.
printf '%-42s %10s %8s %12s %12s\n' command "mean ms" "sd ms" "x baseline" "peak RSS MB"
baseline=""
for i in "${!commands[@]}"; do
  hyperfine -N --warmup 3 --runs "$runs" --export-csv "$work/t.csv" "${commands[$i]}" > /dev/null 2>&1
  # command,mean,stddev,median,user,system,min,max in seconds; the command may hold commas,
  # so count from the end.
  read -r mean sd < <(awk -F, 'NR == 2 { print $(NF - 6) * 1e3, $(NF - 5) * 1e3 }' "$work/t.csv")
  peak=0
  for _ in 1 2 3; do
    # shellcheck disable=SC2086 # the command is several words on purpose
    kb=$(/usr/bin/time -f %M ${commands[$i]} 2>&1 > /dev/null | tail -1)
    if [ "$kb" -gt "$peak" ]; then peak=$kb; fi
  done
  if [[ "${names[$i]}" == baseline:* ]]; then
    baseline=$mean
    ratio="-"
  else
    ratio=$(awk -v t="$mean" -v b="$baseline" 'BEGIN { printf "%.2f", t / b }')
  fi
  printf '%-42s %10.1f %8.1f %12s %12.1f\n' "${names[$i]}" "$mean" "$sd" "$ratio" "$(awk -v kb="$peak" 'BEGIN { print kb / 1024 }')"
done
