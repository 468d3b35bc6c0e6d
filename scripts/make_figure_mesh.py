#!/usr/bin/env python3
"""Writes scenes/figure.obj, the blobby figure of scenes/figure.toml. Deterministic: no
randomness, fixed formatting, so rerunning it reproduces the committed file byte for byte.

The surface is star-shaped around the origin, r(u) = R (1 + sum of smooth bumps), over a
level-4 subdivided icosahedron (2562 vertices, 5120 triangles): a body, a head on top, two
arms and a flattened base. Being closed, it shows every surface normal somewhere (for each
direction, the point furthest along it has that normal), which is what the figure scene is
for: an isotropic glossy object sampled over the whole sphere of normals.

Frame: millimetres, z up, the lowest point at z = 1 (it stands just above a card at z = 0),
faces counter-clockwise seen from outside.

Usage: scripts/make_figure_mesh.py [OUTPUT]   (default: scenes/figure.obj next to this script)
"""
import math
import pathlib
import sys

RADIUS_MM = 32.0
LEVELS = 4

# (unit centre direction, amplitude, sharpness): bump = amplitude * exp(-sharpness (1 - u.c))
BUMPS = [
    ((0.0, 0.0, 1.0), 0.55, 9.0),             # head
    ((0.94, 0.0, 0.34), 0.30, 14.0),          # right arm, raised a little
    ((-0.94, 0.0, 0.34), 0.30, 14.0),         # left arm
    ((0.0, -0.5, 0.866), 0.12, 20.0),         # a nose-like lump facing the viewer
]
BASE_FLATTEN = 0.25  # shrinks the bottom so the figure sits rather than balances


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


def icosphere(levels):
    t = (1.0 + math.sqrt(5.0)) / 2.0
    vertices = [normalize(v) for v in [
        (-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0),
        (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
        (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11),
             (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
             (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9),
             (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        midpoint = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in midpoint:
                va, vb = vertices[a], vertices[b]
                vertices.append(normalize(tuple((x + y) / 2 for x, y in zip(va, vb))))
                midpoint[key] = len(vertices) - 1
            return midpoint[key]

        refined = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            refined += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = refined
    return vertices, faces


def radius(u):
    r = 1.0
    for centre, amplitude, sharpness in BUMPS:
        c = normalize(centre)
        r += amplitude * math.exp(-sharpness * (1.0 - sum(a * b for a, b in zip(u, c))))
    if u[2] < 0.0:
        r *= 1.0 - BASE_FLATTEN * u[2] * u[2]
    return RADIUS_MM * r


def main():
    default = pathlib.Path(__file__).resolve().parent.parent / "scenes" / "figure.obj"
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else default
    directions, faces = icosphere(LEVELS)
    points = [tuple(radius(u) * c for c in u) for u in directions]
    lift = 1.0 - min(p[2] for p in points)
    lines = ["# Blobby figure for scenes/figure.toml, written by scripts/make_figure_mesh.py.",
             f"# {len(points)} vertices, {len(faces)} triangles, millimetres, z up."]
    lines += ["v %.3f %.3f %.3f" % (p[0], p[1], p[2] + lift) for p in points]
    lines += ["f %d %d %d" % (a + 1, b + 1, c + 1) for a, b, c in faces]
    out.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
