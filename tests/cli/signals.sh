#!/usr/bin/env bash
# A signal that ends rfd while it writes leaves no temporary file and no output behind, and
# rfd exits with 128 + the signal: SIGTERM, SIGINT and SIGHUP sent while a pattern is being
# written, and SIGXFSZ from a file-size limit. With SIGXFSZ ignored, as `nohup`-style
# callers may, the write fails instead: an I/O error (exit 3), again with nothing left.
# Usage: signals.sh RFD DESIGN WORK_DIR
set -u
rfd="$1"
design="$2"
work="$3"
rm -rf "$work"
mkdir -p "$work"
"$rfd" --quiet pattern field letters --out "$work/field" > /dev/null || exit 1
status=0
fail() {
  echo "$1" >&2
  ls -a "$work/out" >&2
  status=1
}
encode() { exec "$rfd" --quiet pattern encode "$design" "$work/field" --out "$work/out/p.exr" --allow-partial; }

# Job control on, so that background jobs keep SIGINT (a non-interactive shell ignores it
# in them, and rfd keeps a signal ignored from the start).
set -m
for signal in TERM INT HUP; do
  rm -rf "$work/out"
  mkdir "$work/out"
  encode > /dev/null 2>&1 &
  pid=$!
  # Wait for the temporary pattern file to appear, then signal.
  for _ in $(seq 1 3000); do
    if compgen -G "$work/out/.tmp*" > /dev/null; then break; fi
    sleep 0.01
  done
  compgen -G "$work/out/.tmp*" > /dev/null || fail "SIG$signal: no temporary file appeared"
  kill -s "$signal" "$pid"
  wait "$pid"
  code=$?
  expected=$((128 + $(kill -l "$signal")))
  [ "$code" -eq "$expected" ] || fail "SIG$signal: exit $code, expected $expected"
  [ -z "$(ls -A "$work/out")" ] || fail "SIG$signal: files left behind"
done
set +m

# A 1 MB file-size limit: the kernel sends SIGXFSZ at the first write beyond it.
rm -rf "$work/out"
mkdir "$work/out"
(ulimit -f 1024; encode > /dev/null 2>&1)
code=$?
[ "$code" -eq $((128 + $(kill -l XFSZ))) ] || fail "SIGXFSZ: exit $code, expected $((128 + $(kill -l XFSZ)))"
[ -z "$(ls -A "$work/out")" ] || fail "SIGXFSZ: files left behind"

# The same limit with SIGXFSZ ignored: the write itself fails (EFBIG), as on a full disk.
rm -rf "$work/out"
mkdir "$work/out"
output=$(trap '' XFSZ; ulimit -f 1024; encode 2>&1)
code=$?
[ "$code" -eq 3 ] || fail "file too large: exit $code, expected 3: $output"
[ -z "$(ls -A "$work/out")" ] || fail "file too large: files left behind"
exit "$status"
