"""hbil sample scene "courtyard": open sky, sun, steps, column, gate with lintel, sphere.

    blender -b --factory-startup --python samples/blender/courtyard.py -- \
        --out samples/courtyard --mode main --samples 512 --seed 1

A 40 x 40 m ground plane with an orange back wall (8 m x 2.5 m) and a white
side wall meeting in a corner; three steps (0.18 m rise, 0.35 m run) against
the back wall with a small emissive cube on the top step; a free-standing
column (r = 0.2 m, 3 m); a gate of two pillars with an overhanging lintel; a
blue sphere (r = 0.5 m) resting on the ground; a red box.  Dim blue sky and a
sun from the right.  The camera dollies sideways over frames 1-8 and is aimed
by a Track To constraint at an animated empty (so its matrix only exists after
depsgraph evaluation).
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def build(scene):
    ground = H.diffuse("ground", (0.50, 0.47, 0.42))
    orange = H.diffuse("wall_orange", (0.80, 0.35, 0.10))
    white = H.diffuse("white", (0.72, 0.72, 0.70))
    stone = H.diffuse("stone", (0.60, 0.58, 0.52))
    blue = H.diffuse("sphere_blue", (0.15, 0.30, 0.80))
    red = H.diffuse("box_red", (0.70, 0.10, 0.08))
    glow = H.emission("glow", (1.0, 0.7, 0.4), 10.0)

    H.box("ground", (-20, -20, -0.1), (20, 20, 0), ground)
    H.box("wall_back", (-4.3, 4.0, 0), (4.0, 4.3, 2.5), orange)
    H.box("wall_left", (-4.3, -0.5, 0), (-4.0, 4.0, 2.5), white)

    # three steps against the back wall, x in [0.5, 2.5]
    for i in range(3):
        H.box("step_%d" % i, (0.5, 2.95 + 0.35 * i, 0.18 * i),
              (2.5, 4.0, 0.18 * (i + 1)), white)
    H.box("glow_cube", (2.0, 3.75, 0.54), (2.15, 3.9, 0.69), glow)

    H.cylinder("column", -0.6, 1.2, 0.0, 3.0, 0.2, white, verts=32)

    # gate: two pillars and an overhanging lintel
    H.box("gate_pillar_l", (-3.4, 1.5, 0.0), (-3.1, 1.8, 2.2), stone)
    H.box("gate_pillar_r", (-2.0, 1.5, 0.0), (-1.7, 1.8, 2.2), stone)
    H.box("gate_lintel", (-3.6, 1.25, 2.2), (-1.5, 2.05, 2.45), stone)

    H.sphere("sphere", (0.9, 0.6, 0.5), 0.5, blue)
    H.box("box_red", (2.6, 1.0, 0.0), (3.5, 1.9, 0.9), red, rot_z_deg=30.0)

    H.world(scene, (0.08, 0.10, 0.14))
    H.sun("sun", (-0.60, 0.35, -0.55), strength=3.0, angle_deg=1.0)

    # camera aimed by a constraint at an animated target
    target = bpy.data.objects.new("cam_target", None)
    scene.collection.objects.link(target)
    H.key(target, 1, location=(-0.8, 2.0, 0.8))
    H.key(target, 8, location=(0.3, 2.2, 0.9))
    H.smooth_fcurves(target, 'BEZIER')

    cam = H.camera("Camera", lens_mm=30.0)
    H.key(cam, 1, location=(-2.0, -5.5, 1.6))
    H.key(cam, 8, location=(1.4, -5.0, 1.4))
    H.smooth_fcurves(cam, 'BEZIER')
    con = cam.constraints.new('TRACK_TO')
    con.target = target
    con.track_axis = 'TRACK_NEGATIVE_Z'
    con.up_axis = 'UP_Y'


if __name__ == "__main__":
    H.run("courtyard", build)
