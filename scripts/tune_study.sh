#!/usr/bin/env bash
# The tuning study of docs/results.md ("Tuning Designs III and IV"): `rfd design tune` on a
# design (default: the thesis's Design III) with no plane held (what the parts allow), with
# the three planes the display needs held within design show's tolerance times 1, 0.5, 0.25
# and 0.1, each maximising the efficiency on the axis and the mean over the field, and with
# all four planes held. Prints the table and writes OUTPUT_DIR/tuning.csv and tuning.png (the
# efficiency against the tolerance held). About 2 minutes on one core.
# Usage: scripts/tune_study.sh RFD_BINARY OUTPUT_DIR [DESIGN]
set -euo pipefail
rfd="$1"
out="$2"
design="${3:-$(dirname "$0")/../designs/design3.toml}"
mkdir -p "$out"
three="meso-focus,pattern-image,pattern-focal"

# One tuning: its --json report's figures, or "no spacing" when nothing meets the conditions.
row() {  # planes scale maximise
  local json
  if json=$("$rfd" --quiet design tune "$design" --range 20 --planes "$1" --tolerance-scale "$2" --maximize "$3" \
              --out "$out/tuned.toml" --json 2> /dev/null); then
    python3 -c 'import json,sys; a=json.load(sys.stdin)["after"]; print("%.2f,%.2f,%.2f,%.2f,%d" % (100*a["efficiency_on_axis"], 100*a["efficiency_mean"], 100*a["efficiency_at_half_fov"], a["field_of_view_deg"], len(a["warnings"])))' <<< "$json"
  else
    echo "no spacing,,,,"
  fi
}
given=$("$rfd" --quiet design tune "$design" --planes none --starts 1 --evaluations 10 --out "$out/given.toml" --json |
  python3 -c 'import json,sys; a=json.load(sys.stdin)["before"]; print("%.2f,%.2f,%.2f,%.2f,%d" % (100*a["efficiency_on_axis"], 100*a["efficiency_mean"], 100*a["efficiency_at_half_fov"], a["field_of_view_deg"], len(a["warnings"])))')

echo "planes,tolerance_scale,maximise,on_axis_pct,over_field_pct,half_fov_pct,field_of_view_deg,warnings" > "$out/tuning.csv"
echo "as given,,,$given" >> "$out/tuning.csv"
for maximise in efficiency_on_axis efficiency_mean; do
  echo "none,,$maximise,$(row none 1 $maximise)" >> "$out/tuning.csv"
  for scale in 1 0.5 0.25 0.1; do
    echo "three,$scale,$maximise,$(row $three $scale $maximise)" >> "$out/tuning.csv"
  done
done
echo "all four,1,efficiency_on_axis,$(row all 1 efficiency_on_axis)" >> "$out/tuning.csv"

echo "| planes held | tolerance | maximised | on axis | over the field | at half the FOV | field of view | warnings |"
echo "|---|---|---|---|---|---|---|---|"
tail -n +2 "$out/tuning.csv" | awk -F, '{
  if ($4 == "no spacing") printf "| %s | %s | %s | no spacing meets them | | | | |\n", $1, $2, $3
  else printf "| %s | %s | %s | %s %% | %s %% | %s %% | %s deg | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8 }'

# The chart: efficiency on the axis and over the field against the tolerance the three planes keep.
grep '^three,' "$out/tuning.csv" | awk -F, '$3 == "efficiency_on_axis" { print $2, $4, $5 }' > "$out/on_axis.dat"
grep '^three,' "$out/tuning.csv" | awk -F, '$3 == "efficiency_mean" { print $2, $4, $5 }' > "$out/mean.dat"
bound=$(awk -F, '$1 == "none" && $3 == "efficiency_on_axis" { print $4 }' "$out/tuning.csv")
preset=$(awk -F, '$1 == "as given" { print $4 }' "$out/tuning.csv")
gnuplot <<GNUPLOT
set terminal pngcairo size 800,500
set output "$out/tuning.png"
set title "Tuning $(basename "$design"): three planes held within a fraction of design show's tolerance"
set xlabel "fraction of the tolerance held"
set ylabel "light leaving the display (%)"
set logscale x
set key bottom right
set yrange [0:105]
plot "$out/on_axis.dat" using 1:2 with linespoints title "on the axis (maximised)", \
     "$out/mean.dat" using 1:3 with linespoints title "over the field (maximised)", \
     $bound with lines dashtype 2 title "on the axis, no plane held (the bound)", \
     $preset with lines dashtype 3 title "on the axis, as given"
GNUPLOT
echo "wrote $out/tuning.csv and $out/tuning.png"
