# Sourced by the studies: rendered fields made to look like a camera's, and light sets like a
# handheld capture's.

# degrade FIELD TARGET NOISE QUALITY: a camera-like copy of a rendered field (EXRs and
# field.lp): sRGB, Gaussian noise of NOISE 8-bit codes (each image its own seed), 8 bits,
# PNG (QUALITY png) or JPEG of QUALITY, by oiiotool, two at a time; the light file copied
# with the new names.
degrade() {
  local field="$1" target="$2" noise="$3" quality="$4"
  mkdir -p "$target"
  local i=0 jobs=() ext=jpg
  [ "$quality" = png ] && ext=png
  for exr in "$field"/field_*.exr; do
    i=$((i + 1))
    local name
    name=$(basename "$exr" .exr)
    local args=("$exr" --colorconvert linear sRGB)
    if [ "$noise" != 0 ]; then
      args+=(--noise:type=gaussian:mean=0:stddev=$(awk "BEGIN{print $noise/255}"):seed=$i)
    fi
    args+=(-d uint8)
    if [ "$quality" = png ]; then
      args+=(-o "$target/$name.png")
    else
      args+=(--compression "jpeg:$quality" -o "$target/$name.jpg")
    fi
    oiiotool "${args[@]}" &
    jobs+=($!)
    if [ ${#jobs[@]} -ge 2 ]; then wait "${jobs[0]}"; jobs=("${jobs[@]:1}"); fi
  done
  wait
  sed "s/\.exr/.$ext/" "$field/field.lp" > "$target/field.lp"
}

# handheld_lights COUNT SEED FILE: a light file as a handheld capture gives: COUNT directions
# scattered irregularly between 15 and 70 degrees from the zenith (the photographer's arm
# keeps the lamp off the camera's axis: a gap around the zenith), uneven in azimuth.
handheld_lights() {
  local count="$1" seed="$2" file="$3"
  awk -v n="$count" -v seed="$seed" 'BEGIN {
    srand(seed); pi = 3.14159265358979; print n
    for (i = 0; i < n; i++) {
      theta = (15 + 55 * sqrt(rand())) * pi / 180
      phi = 2 * pi * (i + 0.8 * rand()) / n + 0.3 * sin(3 * i)
      printf "field_%04d.exr %.9f %.9f %.9f\n", i, sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)
    }
  }' > "$file"
}
