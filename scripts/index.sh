# Sourced by scripts/demo.sh and scripts/studies.sh: timed sections on stderr and an index
# of the files written, OUT/INDEX.md, a line per file saying what it is and what to do
# with it. index_entry fails when the file it describes was not written.

index_begin() {  # OUT TITLE INTRO
  index_out="$1"
  mkdir -p "$index_out"
  index_body="$(mktemp)"
  index_times="$(mktemp)"
  printf '# %s\n\n%s\n' "$2" "$3" > "$index_body"
  index_start=$SECONDS
  index_section_name=""
}

index_close_section() {
  if [ -n "$index_section_name" ]; then
    local took=$((SECONDS - index_section_start))
    printf '| %s | %d s |\n' "$index_section_name" "$took" >> "$index_times"
    echo "   ${took} s" >&2
  fi
}

index_section() {  # ID TITLE
  index_close_section
  index_section_name="$2"
  index_section_start=$SECONDS
  echo "== $2" >&2
  printf '\n## %s\n\n' "$2" >> "$index_body"
}

index_entry() {  # PATH TEXT
  if [ ! -e "$index_out/$1" ]; then
    echo "index: $index_out/$1 was not written" >&2
    exit 1
  fi
  printf -- '- [`%s`](%s): %s\n' "$1" "$1" "$2" >> "$index_body"
}

index_end() {
  index_close_section
  local total=$((SECONDS - index_start))
  {
    cat "$index_body"
    printf '\n## Time\n\nOn this machine (%d cores), %d s in all:\n\n| section | time |\n|---|---|\n' "$(nproc)" "$total"
    cat "$index_times"
    printf '\n## Every file\n\nA folder of more than 12 files is one line.\n\n```\n'
    (cd "$index_out" && find . -type f ! -name INDEX.md -printf '%P\t%s\n' | LC_ALL=C sort | awk -F'\t' '
      { dir = $1; sub(/\/[^\/]*$/, "/", dir); if (dir == $1) dir = "";
        path[NR] = $1; size[NR] = $2; folder[NR] = dir; count[dir]++; bytes[dir] += $2 }
      END {
        for (i = 1; i <= NR; ++i) {
          d = folder[i];
          if (count[d] <= 12) printf "%-64s %10.1f kB\n", path[i], size[i] / 1024;
          else if (!(d in shown)) { shown[d] = 1; printf "%-64s %10.1f kB\n", d " (" count[d] " files)", bytes[d] / 1024 }
        }
      }')
    printf '```\n'
  } > "$index_out/INDEX.md"
  rm -f "$index_body" "$index_times"
  echo "written to $index_out in ${total} s; $index_out/INDEX.md lists every file" >&2
}
