"""hbil held-out scene "study": a scene the kernel was never tuned on.

    blender -b --factory-startup --python samples/blender/study.py -- \
        --out /tmp/study --mode main --samples 256 --seed 1 --frames 1-4

A 5 x 4 x 2.6 m room, cream walls with one deep-blue wall and a terracotta
floor; a bookcase of 2 cm boards (thin shelves and dividers) against the
back wall; a table on four 4 cm legs; a window blind of 1.5 cm slats in the
left wall with the sun coming through it; a floor lamp (thin stem, emissive
shade); a sphere on the table.  The camera orbits slowly around the table.
Used once, to check the default preset on data nothing was fitted to
(issue 3's "never seen" criterion); it is not part of the test data.
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def build(scene):
    cream = H.diffuse("cream", (0.78, 0.72, 0.60))
    blue = H.diffuse("wall_blue", (0.08, 0.15, 0.55))
    floor = H.diffuse("terracotta", (0.60, 0.30, 0.18))
    wood = H.diffuse("wood", (0.45, 0.28, 0.14))
    white = H.diffuse("white", (0.80, 0.80, 0.80))
    yellow = H.diffuse("sphere_yellow", (0.80, 0.65, 0.10))
    shade = H.emission("lamp_shade", (1.0, 0.8, 0.55), 6.0)

    t = 0.1
    X0, X1, Y0, Y1, Z1 = -2.5, 2.5, -2.0, 2.0, 2.6
    H.box("floor", (X0 - t, Y0 - 1, -t), (X1 + t, Y1 + t, 0), floor)
    H.box("ceiling", (X0 - t, Y0 - 1, Z1), (X1 + t, Y1 + t, Z1 + t), cream)
    H.box("wall_back", (X0 - t, Y1, 0), (X1 + t, Y1 + t, Z1), cream)
    H.box("wall_right", (X1, Y0 - 1, 0), (X1 + t, Y1, Z1), blue)
    # left wall with a window y in [-0.5, 0.9], z in [0.9, 2.0] and a slatted blind
    H.box("wall_left_low", (X0 - t, Y0 - 1, 0), (X0, Y1, 0.9), cream)
    H.box("wall_left_high", (X0 - t, Y0 - 1, 2.0), (X0, Y1, Z1), cream)
    H.box("wall_left_front", (X0 - t, Y0 - 1, 0.9), (X0, -0.5, 2.0), cream)
    H.box("wall_left_back", (X0 - t, 0.9, 0.9), (X0, Y1, 2.0), cream)
    for i in range(12):
        z = 0.95 + i * 0.09
        H.box("blind_%02d" % i, (X0 + 0.02, -0.5, z), (X0 + 0.07, 0.9, z + 0.015), white)

    # bookcase: 2 cm boards, x in [-1.6, 0.4], depth 0.3, height 2.0
    bx0, bx1, by0, by1, bh, b = -1.6, 0.4, Y1 - 0.3, Y1, 2.0, 0.02
    for k in range(6):
        z = k * (bh - b) / 5
        H.box("shelf_%d" % k, (bx0, by0, z), (bx1, by1, z + b), wood)
    for k in range(5):
        x = bx0 + k * (bx1 - bx0 - b) / 4
        H.box("divider_%d" % k, (x, by0, 0), (x + b, by1, bh), wood)

    # table on thin legs, sphere on it
    tx0, tx1, ty0, ty1, th = 0.2, 1.4, -0.6, 0.2, 0.75
    H.box("table_top", (tx0, ty0, th - 0.03), (tx1, ty1, th), wood)
    for i, (x, y) in enumerate([(tx0 + 0.05, ty0 + 0.05), (tx1 - 0.05, ty0 + 0.05),
                                (tx0 + 0.05, ty1 - 0.05), (tx1 - 0.05, ty1 - 0.05)]):
        H.box("leg_%d" % i, (x - 0.02, y - 0.02, 0), (x + 0.02, y + 0.02, th - 0.03), wood)
    H.sphere("sphere", (0.9, -0.2, th + 0.2), 0.2, yellow)

    # floor lamp: thin stem, emissive shade
    H.cylinder("lamp_stem", 1.9, 1.4, 0.0, 1.5, 0.012, white, verts=16)
    H.cylinder("lamp_shade", 1.9, 1.4, 1.5, 1.75, 0.15, shade, verts=24)

    H.world(scene, (0.06, 0.07, 0.09))
    H.sun("sun", (0.75, 0.10, -0.65), strength=4.0, angle_deg=1.0)

    cam = H.camera("Camera", lens_mm=22.0)
    H.key(cam, 1, location=(1.6, -2.6, 1.55),
          rotation_euler=(math.radians(76.0), 0.0, math.radians(22.0)))
    H.key(cam, 4, location=(0.6, -2.8, 1.45),
          rotation_euler=(math.radians(77.0), 0.0, math.radians(8.0)))
    H.smooth_fcurves(cam, 'BEZIER')


if __name__ == "__main__":
    H.run("study", build)
