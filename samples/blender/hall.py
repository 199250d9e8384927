"""hbil held-out scene "hall": a large interior lit through a skylight.

    blender -b --factory-startup --python samples/blender/hall.py -- \
        --out /tmp/scenes/hall --mode main --samples 128 --seed 1 --frames 1-4

A 20 x 30 x 8 m hall (x in [-10, 10], y in [-15, 15]) with a pale concrete
floor, walls of different albedos (warm white, grey-blue, brick red, sand)
and a 0.4 m thick ceiling cut by a 3 x 24 m skylight strip along the hall's
axis.  Two rows of 0.6 m square columns (x = -5 and 5, every 5 m) carry two
0.6 x 0.8 m beams under the ceiling.  The sun comes through the skylight at
about 60 degrees elevation and lays a bright strip across the floor, a
column row and a few large crates (1.5 - 3 m, varied colours), which bounce
light over the whole hall; a dim sky adds light through the opening.  The
camera stands inside at 2 m height near one end wall, looking along the hall
(objects from 3 to 28 m away), and moves slowly forward over frames 1-4.
A held-out validation scene for the automatic gather radius / thickness
defaults (scene scale: metres to tens of metres, interior); it is not test data.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def build(scene):
    floor = H.diffuse("concrete_floor", (0.55, 0.53, 0.50))
    warm = H.diffuse("wall_warm", (0.80, 0.75, 0.65))
    bluegrey = H.diffuse("wall_bluegrey", (0.35, 0.42, 0.55))
    brick = H.diffuse("wall_brick", (0.55, 0.25, 0.15))
    sand = H.diffuse("wall_sand", (0.70, 0.60, 0.40))
    ceil = H.diffuse("ceiling", (0.70, 0.70, 0.70))
    column = H.diffuse("column", (0.65, 0.63, 0.60))
    crates = [H.diffuse("crate_wood", (0.55, 0.35, 0.15)),
              H.diffuse("crate_green", (0.15, 0.45, 0.20)),
              H.diffuse("crate_blue", (0.12, 0.22, 0.60)),
              H.diffuse("crate_yellow", (0.80, 0.65, 0.10)),
              H.diffuse("crate_white", (0.85, 0.85, 0.85))]

    t = 0.3
    X0, X1, Y0, Y1, Z1 = -10.0, 10.0, -15.0, 15.0, 8.0
    H.box("floor", (X0 - t, Y0 - t, -t), (X1 + t, Y1 + t, 0.0), floor)
    H.box("wall_left", (X0 - t, Y0, 0.0), (X0, Y1, Z1), warm)
    H.box("wall_right", (X1, Y0, 0.0), (X1 + t, Y1, Z1), bluegrey)
    H.box("wall_far", (X0 - t, Y1, 0.0), (X1 + t, Y1 + t, Z1), brick)
    H.box("wall_near", (X0 - t, Y0 - t, 0.0), (X1 + t, Y0, Z1), sand)
    # ceiling with a skylight x in [-1.5, 1.5], y in [-12, 12]
    c0, c1 = Z1, Z1 + 0.4
    H.box("ceil_left", (X0 - t, Y0 - t, c0), (-1.5, Y1 + t, c1), ceil)
    H.box("ceil_right", (1.5, Y0 - t, c0), (X1 + t, Y1 + t, c1), ceil)
    H.box("ceil_near", (-1.5, Y0 - t, c0), (1.5, -12.0, c1), ceil)
    H.box("ceil_far", (-1.5, 12.0, c0), (1.5, Y1 + t, c1), ceil)

    # two rows of 0.6 m square columns and the beams on them
    for row, x in (("l", -5.0), ("r", 5.0)):
        for k in range(5):
            y = -10.0 + 5.0 * k
            H.box("col_%s%d" % (row, k), (x - 0.3, y - 0.3, 0.0), (x + 0.3, y + 0.3, Z1 - 0.8),
                  column)
        H.box("beam_%s" % row, (x - 0.3, Y0, Z1 - 0.8), (x + 0.3, Y1, Z1), column)

    # large crates (x0, y0, sx, sy, sz, material, yaw)
    for i, (x, y, sx, sy, sz, m, yaw) in enumerate([
            (-3.0, -4.0, 2.0, 2.0, 2.0, 0, 0.0), (-2.6, -4.2, 1.5, 1.5, 1.5, 3, 20.0),
            (3.8, 2.0, 3.0, 1.5, 1.5, 2, -10.0), (6.5, -2.0, 2.0, 3.0, 2.5, 1, 0.0),
            (-7.5, 6.0, 2.5, 2.5, 2.0, 4, 15.0), (2.0, 9.0, 2.0, 2.0, 3.0, 0, 35.0)]):
        z0 = 2.0 if i == 1 else 0.0  # the second crate sits on the first
        H.box("crate_%d" % i, (x - sx / 2, y - sy / 2, z0), (x + sx / 2, y + sy / 2, z0 + sz),
              crates[m], rot_z_deg=yaw)

    H.world(scene, (0.30, 0.40, 0.60), strength=1.0)
    H.sun("sun", (0.45, 0.15, -0.88), strength=5.0, angle_deg=1.0)

    cam = H.camera("Camera", lens_mm=20.0)
    p1, p4 = (-1.5, -13.5, 2.0), (-0.6, -12.3, 2.0)
    H.key_aimed(cam, 1, p1, (1.5, 10.0, 3.0))
    H.key_aimed(cam, 4, p4, (1.0, 10.0, 3.2))
    H.smooth_fcurves(cam, 'BEZIER')


if __name__ == "__main__":
    H.run("hall", build)
