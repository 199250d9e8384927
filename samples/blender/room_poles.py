"""hbil sample scene "room_poles": a 4 x 3.5 x 3 m room with thin poles and a fence.

    blender -b --factory-startup --python samples/blender/room_poles.py -- \
        --out samples/room_poles --mode main --samples 512 --seed 1

Room interior x in [-2, 2], y in [-2, 1.5], z in [0, 3] (metres, Z up).  The
front (y = -2) is open; the red left wall has a window through which a sun
shines onto the floor; a small area light hangs under the ceiling; the right
wall is green.  Five thin poles (3-5 cm) stand free in the room, a slatted
fence (3 cm slats, 5 cm gaps) stands 26 cm in front of the back wall, two boxes
and a small emissive cube sit on the floor.  The camera dollies into the room
over frames 1-8 while panning slightly (keyframed location/rotation, Bezier).
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def build(scene):
    grey = H.diffuse("floor_grey", (0.55, 0.55, 0.55))
    white = H.diffuse("white", (0.75, 0.75, 0.75))
    red = H.diffuse("wall_red", (0.70, 0.08, 0.06))
    green = H.diffuse("wall_green", (0.10, 0.55, 0.12))
    pole = H.diffuse("pole", (0.80, 0.80, 0.78))
    fence = H.diffuse("fence_yellow", (0.75, 0.60, 0.20))
    blue = H.diffuse("box_blue", (0.15, 0.30, 0.70))
    boxgrey = H.diffuse("box_grey", (0.60, 0.58, 0.55))
    glow = H.emission("glow", (1.0, 0.6, 0.3), 8.0)

    t = 0.1  # wall thickness
    H.box("floor", (-2 - t, -2, -t), (2 + t, 1.5 + t, 0), grey)
    H.box("ceiling", (-2 - t, -2, 3), (2 + t, 1.5 + t, 3 + t), white)
    H.box("wall_back", (-2 - t, 1.5, 0), (2 + t, 1.5 + t, 3), white)
    H.box("wall_right", (2, -2, 0), (2 + t, 1.5, 3), green)
    # left wall with a window y in [-0.6, 0.6], z in [1.0, 2.2]
    H.box("wall_left_low", (-2 - t, -2, 0), (-2, 1.5, 1.0), red)
    H.box("wall_left_high", (-2 - t, -2, 2.2), (-2, 1.5, 3), red)
    H.box("wall_left_front", (-2 - t, -2, 1.0), (-2, -0.6, 2.2), red)
    H.box("wall_left_back", (-2 - t, 0.6, 1.0), (-2, 1.5, 2.2), red)

    # thin poles: (x, y, radius, height)
    for i, (x, y, r, h) in enumerate([(-1.00, 0.20, 0.020, 2.3),
                                      (-0.45, -0.35, 0.015, 2.3),
                                      (0.35, 0.45, 0.025, 3.0),   # floor to ceiling
                                      (0.90, -0.15, 0.020, 2.3),
                                      (1.35, 0.75, 0.020, 2.3)]):
        H.cylinder("pole_%d" % i, x, y, 0.0, h, r, pole)

    # fence: 3 cm slats, 8 cm pitch, 1.3 m tall, two rails behind them
    x0, x1, pitch, w = -1.4, 0.6, 0.08, 0.03
    n = int(round((x1 - x0) / pitch)) + 1
    for i in range(n):
        x = x0 + i * pitch
        H.box("fence_slat_%02d" % i, (x - w / 2, 1.19, 0.0), (x + w / 2, 1.21, 1.3), fence)
    for j, z in enumerate((0.15, 1.05)):
        H.box("fence_rail_%d" % j, (x0 - 0.05, 1.21, z), (x1 + 0.05, 1.24, z + 0.04), fence)

    H.box("box_blue", (-1.5, -1.0, 0.0), (-0.9, -0.4, 0.6), blue)
    H.box("box_grey", (1.2 - 0.4, 0.9 - 0.225, 0.0), (1.2 + 0.4, 0.9 + 0.225, 0.35),
          boxgrey, rot_z_deg=20.0)
    H.box("glow_cube", (1.14, 0.84, 0.35), (1.26, 0.96, 0.47), glow, rot_z_deg=20.0)

    H.world(scene, (0.05, 0.05, 0.055))
    H.sun("sun", (0.78, 0.15, -0.60), strength=4.0, angle_deg=1.0)
    H.area_light("ceiling_light", (0.0, -0.3, 2.95), size=0.8, power=60.0,
                 color=(1.0, 0.95, 0.9))

    cam = H.camera("Camera", lens_mm=20.0)
    H.key(cam, 1, location=(0.70, -1.90, 1.60),
          rotation_euler=(math.radians(74.0), 0.0, math.radians(16.0)))
    H.key(cam, 8, location=(0.05, -1.20, 1.50),
          rotation_euler=(math.radians(76.0), 0.0, math.radians(4.0)))
    H.smooth_fcurves(cam, 'BEZIER')


if __name__ == "__main__":
    H.run("room_poles", build)
