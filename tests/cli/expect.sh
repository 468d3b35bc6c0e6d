#!/usr/bin/env bash
# End-to-end check of one rfd command line: exit code and a piece of the output.
# Usage: expect.sh EXIT_CODE TEXT -- COMMAND [ARGS...]
#   TEXT (an extended regular expression) must match the command's stdout or stderr.
set -u
expected_code="$1"
expected_text="$2"
shift 3
output="$("$@" 2>&1)"
code=$?
status=0
if [ "$code" -ne "$expected_code" ]; then
  echo "exit code $code, expected $expected_code" >&2
  status=1
fi
if ! grep -qE -- "$expected_text" <<<"$output"; then
  echo "output lacks: $expected_text" >&2
  status=1
fi
if [ "$status" -ne 0 ]; then
  echo "--- command: $*" >&2
  echo "$output" >&2
fi
exit "$status"
