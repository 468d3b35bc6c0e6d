# Light directions that sample area lights densely, for rendering their ground truth on the
# light stage: a golden-angle spiral of directions `step` degrees apart (default 0.9) over
# each light's cap widened by 2 degrees, so that interpolating them anywhere inside the cap
# never reaches outside it. `rfd relight eval FIELD --reference THESE --light T,P,R` then
# scores a field under the area light against the stage's own rendering of it, where a
# relit reference field would carry its own interpolation error (a glint narrower than the
# reference's spacing lands in it at the weight of a whole spacing).
#
# In: one light per line, "THETA,PHI,RADIUS" in degrees (the field frame, core/sphere.hpp).
# Out: a light file (relight/field.hpp): the count, then "name x y z" per direction.
# Usage: printf '30,120,7.5\n' | awk -v step=1.2 -f scripts/cap_lights.awk > caps.lp
BEGIN {
  FS = ","; pi = atan2(0, -1); golden = pi * (3 - sqrt(5))
  if (step == "") step = 0.9
  step_rad = step * pi / 180
}
NF >= 3 {
  t = $1 * pi / 180; p = $2 * pi / 180; cap = ($3 + 2) * pi / 180
  cx = sin(t) * cos(p); cy = sin(t) * sin(p); cz = cos(t)
  # A frame (u, v) across the centre c: u = z x c (or x x c near the pole), v = c x u.
  if (cz > 0.9 || cz < -0.9) { ux = 0; uy = cz; uz = -cy } else { ux = -cy; uy = cx; uz = 0 }
  n = sqrt(ux * ux + uy * uy + uz * uz); ux /= n; uy /= n; uz /= n
  vx = cy * uz - cz * uy; vy = cz * ux - cx * uz; vz = cx * uy - cy * ux
  count = int(2 * pi * (1 - cos(cap)) / (step_rad * step_rad)) + 1
  for (i = 0; i < count; ++i) {
    z = 1 - (1 - cos(cap)) * (i + 0.5) / count; r = sqrt(1 - z * z); a = golden * i
    lines[total++] = sprintf("cap_%d_%d %.17g %.17g %.17g", NR, i, z * cx + r * (cos(a) * ux + sin(a) * vx),
      z * cy + r * (cos(a) * uy + sin(a) * vy), z * cz + r * (cos(a) * uz + sin(a) * vz))
  }
}
END {
  print total
  for (i = 0; i < total; ++i) print lines[i]
}
