"""hbil held-out scene "tabletop": small objects on a table, seen from close up.

    blender -b --factory-startup --python samples/blender/tabletop.py -- \
        --out /tmp/scenes/tabletop --mode main --samples 128 --seed 1 --frames 1-4

A 1.2 x 0.8 m table top (3 cm thick, top face at z = 0, light wood) with
objects of 2 - 15 cm on it: cubes of 2, 4 and 8 cm, spheres of 3, 5 and 10 cm
diameter, a 5 cm wide, 12 cm tall cylinder, a small arch (two 2 x 2 x 6 cm
piers, 10 cm lintel), a thin 3 mm plate (10 x 8 cm) standing upright, two
hexagonal pencils of 7 mm lying on the table and a 15 x 10 x 1 cm book; varied
albedos.  A 0.4 m square area light 0.8 m above the table, off to the left,
and a dim world light it; there is no floor or wall (the table floats in the
dim world), so nothing else is within 2 m.  A 50 mm lens 0.55 - 0.9 m from
what it sees (median depth 0.66 m), looking down at about 35 degrees; the
camera moves slowly sideways over frames 1-4.
A held-out validation scene for the automatic gather radius / thickness
defaults (scene scale: centimetres); it is not test data.
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def cube(name, x, y, size, mat, yaw=0.0, z0=0.0):
    h = size / 2
    return H.box(name, (x - h, y - h, z0), (x + h, y + h, z0 + size), mat, rot_z_deg=yaw)


def pencil(name, x, y, length, yaw_deg, mat):
    """Hexagonal pencil of 7 mm across the corners, lying on the table."""
    ob = H.cylinder(name, 0.0, 0.0, -length / 2, length / 2, 0.0035, mat, verts=6)
    # lay the axis along y (a flat side of the hexagon down), then yaw
    ob.rotation_euler = (math.radians(90.0), 0.0, math.radians(yaw_deg))
    ob.location = (x, y, 0.0035 * math.cos(math.radians(30.0)))
    return ob


def build(scene):
    wood = H.diffuse("table_wood", (0.62, 0.45, 0.28))
    red = H.diffuse("red", (0.75, 0.10, 0.08))
    blue = H.diffuse("blue", (0.10, 0.20, 0.70))
    white = H.diffuse("white", (0.85, 0.85, 0.85))
    yellow = H.diffuse("yellow", (0.85, 0.70, 0.10))
    green = H.diffuse("green", (0.15, 0.55, 0.20))
    grey = H.diffuse("grey", (0.40, 0.40, 0.42))
    black = H.diffuse("black", (0.05, 0.05, 0.05))
    orange = H.diffuse("orange", (0.85, 0.40, 0.08))

    H.box("table_top", (-0.6, -0.4, -0.03), (0.6, 0.4, 0.0), wood)

    cube("cube_8cm", -0.12, 0.08, 0.08, red, yaw=20.0)
    cube("cube_4cm", -0.03, 0.02, 0.04, white, yaw=-10.0)
    cube("cube_2cm", -0.03, 0.02, 0.02, yellow, yaw=35.0, z0=0.04)  # on the 4 cm cube
    cube("cube_2cm_b", 0.10, -0.06, 0.02, blue, yaw=5.0)
    H.sphere("sphere_10cm", (0.10, 0.12, 0.05), 0.05, yellow)
    H.sphere("sphere_5cm", (0.02, -0.07, 0.025), 0.025, blue)
    H.sphere("sphere_3cm", (-0.17, -0.04, 0.015), 0.015, white)
    H.cylinder("cylinder", -0.22, 0.12, 0.0, 0.12, 0.025, green, verts=32)

    # small arch: two piers and a lintel
    H.box("arch_pier_l", (0.17, -0.01, 0.0), (0.19, 0.01, 0.06), white)
    H.box("arch_pier_r", (0.25, -0.01, 0.0), (0.27, 0.01, 0.06), white)
    H.box("arch_lintel", (0.17, -0.01, 0.06), (0.27, 0.01, 0.08), white)

    # thin plate standing upright (3 mm), slightly turned
    H.box("plate_3mm", (-0.11, -0.0315, 0.0), (-0.01, -0.0285, 0.08), orange, rot_z_deg=-25.0)

    pencil("pencil_a", 0.05, -0.13, 0.15, 70.0, yellow)
    pencil("pencil_b", -0.08, -0.13, 0.15, 100.0, green)
    H.box("book", (0.22, 0.08, 0.0), (0.32, 0.23, 0.01), grey, rot_z_deg=10.0)
    cube("cube_4cm_dark", 0.22, 0.16, 0.04, black, yaw=-30.0, z0=0.01)  # on the book

    H.world(scene, (0.05, 0.055, 0.07), strength=1.0)
    H.area_light("key_light", (-0.45, -0.15, 0.8), 0.4, 15.0, color=(1.0, 0.95, 0.85),
                 travel_dir=(0.45, 0.15, -0.8))

    cam = H.camera("Camera", lens_mm=50.0)
    p1, p4 = (-0.06, -0.54, 0.40), (0.09, -0.52, 0.38)
    H.key_aimed(cam, 1, p1, (0.02, 0.0, 0.02))
    H.key_aimed(cam, 4, p4, (0.05, 0.0, 0.02))
    H.smooth_fcurves(cam, 'BEZIER')


if __name__ == "__main__":
    H.run("tabletop", build)
