#!/usr/bin/env bash
# Runs the README's shell blocks as a user types them: in order, in a fresh folder that sees
# the repository's bundled data, with `build/` pointing at the programs under test. The
# walk-through's file names must chain and every command must succeed. The first block
# (`make demo`, `make test`) is what CI itself runs; here its targets are only checked to
# exist (make --dry-run).
# Usage: tests/cli/readme.sh SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
src="$1"
build="$2"
work="$3"

rm -rf "$work"
mkdir -p "$work"
for data in designs scenes printers holders examples; do ln -s "$src/$data" "$work/$data"; done
ln -s "$build" "$work/build"

# One file per ```sh block, numbered from 1.
awk -v dir="$work" '
  /^```sh$/ { inside = 1; n++; file = sprintf("%s/block%02d.sh", dir, n); printf "" > file; next }
  /^```$/   { inside = 0; next }
  inside    { print >> file }
' "$src/README.md"

blocks=("$work"/block*.sh)
if [ "${#blocks[@]}" -lt 2 ]; then
  echo "readme: expected the set-up block and at least one more, found ${#blocks[@]}" >&2
  exit 1
fi

# The set-up block: `make TARGET` lines only, each target known to the Makefile.
while read -r line; do
  command="${line%%#*}"
  [ -z "${command// /}" ] && continue
  read -r -a words <<< "$command"
  if [ "${words[0]}" != make ] || [ "${#words[@]}" -ne 2 ]; then
    echo "readme: the set-up block should hold 'make TARGET' lines, got: $line" >&2
    exit 1
  fi
  make -C "$src" --dry-run "${words[1]}" > /dev/null
done < "${blocks[0]}"

# The rest, in one shell, so that `export` and files carry from block to block.
script="$work/walkthrough.sh"
{
  echo 'set -euo pipefail'
  echo 'trap '\''echo "readme: failed: $BASH_COMMAND" >&2'\'' ERR'
  cat "${blocks[@]:1}"
} > "$script"
cd "$work"
bash "$script" > "$work/walkthrough.log"
echo "readme: ${#blocks[@]} blocks ran"
