"""hbil held-out scene "corridor": a long gallery lit by tall windows on one side.

    blender -b --factory-startup --python samples/blender/corridor.py -- \
        --out /tmp/scenes/corridor --mode main --samples 256 --seed 1 --frames 1-4

A 4 x 36 x 4.5 m gallery (x in [-2, 2], y in [-18, 18]) with a dark wooden
floor, a white plastered window wall (x = 2) cut by five 1.6 x 3 m windows
every 6 m, a green-grey inner wall (x = -2), an ochre far wall and a pale
ceiling.  The low sun comes through the windows at about 25 degrees and lays
bright trapezoids across the floor and the inner wall; most of what lights the
rest of the gallery is that light bounced along its length.  Benches (0.45 m)
stand along the inner wall and three plinths (1 m) carry pale blocks.  The
camera stands at 1.6 m near the near end and looks down the gallery (objects
from 1 to 34 m away), moving slowly forward over frames 1-4.
A held-out validation scene for the unseen fill's level (scene scale: a long
enclosed interior); it is not test data.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def build(scene):
    floor = H.diffuse("floor_wood", (0.30, 0.20, 0.12))
    plaster = H.diffuse("wall_plaster", (0.82, 0.80, 0.76))
    inner = H.diffuse("wall_inner", (0.40, 0.48, 0.40))
    far = H.diffuse("wall_far", (0.75, 0.55, 0.25))
    ceil = H.diffuse("ceiling", (0.78, 0.78, 0.75))
    bench = H.diffuse("bench", (0.25, 0.25, 0.28))
    plinth = H.diffuse("plinth", (0.60, 0.60, 0.62))
    block = H.diffuse("block", (0.85, 0.82, 0.70))

    t = 0.3
    X0, X1, Y0, Y1, Z1 = -2.0, 2.0, -18.0, 18.0, 4.5
    H.box("floor", (X0 - t, Y0 - t, -t), (X1 + t, Y1 + t, 0.0), floor)
    H.box("ceiling", (X0 - t, Y0 - t, Z1), (X1 + t, Y1 + t, Z1 + t), ceil)
    H.box("wall_inner", (X0 - t, Y0, 0.0), (X0, Y1, Z1), inner)
    H.box("wall_far", (X0 - t, Y1, 0.0), (X1 + t, Y1 + t, Z1), far)
    H.box("wall_near", (X0 - t, Y0 - t, 0.0), (X1 + t, Y0, Z1), plaster)
    # window wall: piers between five windows (y centres -12 .. 12), sill 0.8, head 3.8
    ys = [-12.0 + 6.0 * k for k in range(5)]
    edges = [Y0] + [e for y in ys for e in (y - 0.8, y + 0.8)] + [Y1]
    for k in range(0, len(edges), 2):
        H.box("pier_%d" % (k // 2), (X1, edges[k], 0.0), (X1 + t, edges[k + 1], Z1), plaster)
    for k, y in enumerate(ys):
        H.box("sill_%d" % k, (X1, y - 0.8, 0.0), (X1 + t, y + 0.8, 0.8), plaster)
        H.box("head_%d" % k, (X1, y - 0.8, 3.8), (X1 + t, y + 0.8, Z1), plaster)

    for k in range(4):
        y = -10.0 + 7.0 * k
        H.box("bench_%d" % k, (X0, y - 1.0, 0.0), (X0 + 0.45, y + 1.0, 0.45), bench)
    for k, (y, s) in enumerate([(-6.0, 0.5), (2.0, 0.7), (10.0, 0.6)]):
        H.box("plinth_%d" % k, (0.3, y - 0.3, 0.0), (0.9, y + 0.3, 1.0), plinth)
        H.box("block_%d" % k, (0.6 - s / 2, y - s / 2, 1.0), (0.6 + s / 2, y + s / 2, 1.0 + s),
              block, rot_z_deg=15.0 * k)

    H.world(scene, (0.35, 0.45, 0.65), strength=0.8)
    H.sun("sun", (-0.85, 0.25, -0.45), strength=4.0, angle_deg=1.0)

    cam = H.camera("Camera", lens_mm=24.0)
    p1, p4 = (-0.4, -16.5, 1.6), (-0.2, -15.3, 1.6)
    H.key_aimed(cam, 1, p1, (0.3, 10.0, 1.5))
    H.key_aimed(cam, 4, p4, (0.4, 10.0, 1.5))
    H.smooth_fcurves(cam, 'BEZIER')


if __name__ == "__main__":
    H.run("corridor", build)
