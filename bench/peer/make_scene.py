#!/usr/bin/env python3
"""Writes bench/peer/scene/stones.obj: the geometry of the peer-comparison scene.

A ground of two parts (a 100 m square, and around it a ring out to a 40 km square, which hides
the lower hemisphere from every point of the scene: restauro's sky has nothing below the horizon,
Mitsuba's `constant` emitter is a whole sphere; only the band between the horizon and the
ground's edge differs, 1.6·10⁻⁴ rad seen from the camera's 3.2 m, about 0.03 % of the image's
mean luminance, Mitsuba brighter) and seven Lambertian stone blocks, each a closed
box of 12 triangles wound anticlockwise seen from outside (outward normals: Mitsuba's `diffuse`
is one-sided, restauro's Lambert two-sided). One OBJ part (`usemtl`) per material.

Run once; the output is committed. Standard library only.
"""
import math
import pathlib

HERE = pathlib.Path(__file__).resolve().parent

# (part, centre x, y, size x, y, z, rotation about +Z in degrees, base height)
BLOCKS = [
    ("limestone", -2.6, 1.0, 1.6, 1.0, 1.2, 15.0, 0.0),
    ("limestone", -2.5, 1.1, 1.2, 0.8, 0.7, 25.0, 1.2),
    ("sandstone", 0.4, 2.2, 1.0, 1.0, 2.6, -10.0, 0.0),
    ("sandstone", 2.6, 0.2, 2.0, 0.9, 0.8, 40.0, 0.0),
    ("travertine", 0.9, -0.9, 0.8, 0.8, 0.6, 5.0, 0.0),
    ("travertine", -0.6, 4.5, 3.0, 1.2, 1.8, 0.0, 0.0),
    ("limestone", 3.4, 3.6, 1.0, 1.4, 1.5, -30.0, 0.0),
]

INNER = 50.0
# Not farther: with a 400 km ring both renderers (32-bit floats) go wrong near the horizon
# (restauro shows the distant ground black, self-shadowed; the means differ by 2.5 %).
OUTER = 20000.0


def box(cx, cy, sx, sy, sz, rot_deg, z0):
    c, s = math.cos(math.radians(rot_deg)), math.sin(math.radians(rot_deg))
    verts = []
    for k in range(8):
        x = (-0.5 if k & 1 == 0 else 0.5) * sx
        y = (-0.5 if k & 2 == 0 else 0.5) * sy
        z = z0 + (0.0 if k & 4 == 0 else sz)
        verts.append((cx + c * x - s * y, cy + s * x + c * y, z))
    # Quads as vertex indices (bit 0: +x, bit 1: +y, bit 2: +z), anticlockwise from outside.
    quads = [
        (0, 2, 3, 1),  # bottom, -z
        (4, 5, 7, 6),  # top, +z
        (0, 1, 5, 4),  # -y
        (2, 6, 7, 3),  # +y
        (0, 4, 6, 2),  # -x
        (1, 3, 7, 5),  # +x
    ]
    return verts, quads


def ground():
    a, b = INNER, OUTER
    verts = [(-a, -a, 0), (a, -a, 0), (a, a, 0), (-a, a, 0),
             (-b, -b, 0), (b, -b, 0), (b, b, 0), (-b, b, 0)]
    quads = [(0, 1, 2, 3),            # the inner square, facing up
             (4, 5, 1, 0), (5, 6, 2, 1), (6, 7, 3, 2), (7, 4, 0, 3)]  # the ring
    return verts, quads


def main():
    parts = {}
    parts.setdefault("ground", []).append(ground())
    for part, *geom in BLOCKS:
        parts.setdefault(part, []).append(box(*geom))
    lines = ["# The peer-comparison scene (bench/peer): written by make_scene.py; Z up, metres."]
    base = 1
    for part, shapes in parts.items():
        lines.append(f"o {part}")
        lines.append(f"usemtl {part}")
        for verts, quads in shapes:
            lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in verts]
            for q in quads:
                i = [base + k for k in q]
                lines.append(f"f {i[0]} {i[1]} {i[2]}")
                lines.append(f"f {i[0]} {i[2]} {i[3]}")
            base += len(verts)
    (HERE / "scene" / "stones.obj").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
