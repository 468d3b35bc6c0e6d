#!/usr/bin/env bash
# Every file of the source tree that the docs, the README, HACKING.md, cmake/layers.txt or a
# comment in the code names exists: no page or header points to a file that is not there.
# Names with a placeholder (fuzz_NAME.cpp, designN.toml) and paths inside an output folder
# that rfd writes (predict/..., three.js's examples/js/) are not the tree's; scripts/, which
# name the demo's outputs, and tests/data/ (files that break rules on purpose) are not read.
# Usage: doc_references.sh SOURCE_DIR
set -euo pipefail
cd "$1"
folders='core|optics|relight|patterns|print|predict|holders|project|cli|tests|bench|fuzz|docs|scripts|cmake|designs|scenes|printers|examples'
checked=0
missing=()
while IFS= read -r name; do
  case "$name" in
    *NAME*|*designN*|examples/js/*|predict/tolerance/*|predict/compare/*|predict/optimize/*) continue ;;
  esac
  checked=$((checked + 1))
  [ -e "$name" ] || missing+=("$name")
done < <(grep -ohP "(?<![\w./-])($folders)/[\w./-]+\.(hpp|cpp|md|toml|sh|cmake|txt|js|json)\b" \
           README.md HACKING.md docs/*.md cmake/layers.txt \
           $(find core optics relight patterns print predict holders project cli tests bench fuzz cmake \
               -path tests/data -prune -o \( -name '*.hpp' -o -name '*.cpp' -o -name '*.cmake' -o -name '*.sh' \) -print) |
         sort -u)
if [ ${#missing[@]} -gt 0 ]; then
  echo "FAIL: named but not in the tree: ${missing[*]}" >&2
  exit 1
fi
[ "$checked" -ge 100 ] || { echo "FAIL: only $checked file names found: is the pattern broken?" >&2; exit 1; }
echo "doc references: all $checked file names exist"
