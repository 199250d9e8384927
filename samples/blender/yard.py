"""hbil held-out scene "yard": sheds, crates and a wall on open ground under the sky.

    blender -b --factory-startup --python samples/blender/yard.py -- \
        --out /tmp/scenes/yard --mode main --samples 256 --seed 1 --frames 1-4

A 60 x 60 m sandy ground with, 10 - 27 m from the camera: a 2.5 m tall, 14 m
long brick wall, two sheds (4 x 3 x 3 m, pale and blue), a stack of wooden
crates (1 - 1.2 m), a white van-sized block (5 x 2 x 2.2 m) and a few
concrete barriers (0.8 m).  A sun at about 40 degrees and a bright sky light
it; nothing closes the space above, and the sky fills the top third of the
frame.  The camera stands at 1.7 m and looks slightly down across the yard,
panning a little over frames 1-4.
A held-out validation scene for the unseen fill's level (scene scale: metres,
outdoors, open); it is not test data.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def build(scene):
    ground = H.diffuse("ground_sand", (0.55, 0.48, 0.36))
    brick = H.diffuse("brick", (0.50, 0.22, 0.14))
    pale = H.diffuse("shed_pale", (0.80, 0.78, 0.72))
    blue = H.diffuse("shed_blue", (0.15, 0.25, 0.55))
    wood = H.diffuse("crate_wood", (0.55, 0.38, 0.20))
    white = H.diffuse("van_white", (0.88, 0.88, 0.88))
    concrete = H.diffuse("concrete", (0.50, 0.50, 0.48))

    H.box("ground", (-30.0, -30.0, -0.3), (30.0, 30.0, 0.0), ground)
    H.box("wall", (-9.0, 14.0, 0.0), (5.0, 14.3, 2.5), brick)
    H.box("shed_a", (-8.0, 8.0, 0.0), (-4.0, 11.0, 3.0), pale, rot_z_deg=8.0)
    H.box("shed_b", (3.0, 16.0, 0.0), (7.0, 19.0, 3.0), blue, rot_z_deg=-12.0)
    for k, (x, y, z, s) in enumerate([(0.0, 7.0, 0.0, 1.2), (1.3, 7.2, 0.0, 1.1),
                                      (0.6, 7.1, 1.2, 1.0), (-1.2, 8.4, 0.0, 1.0)]):
        H.box("crate_%d" % k, (x - s / 2, y - s / 2, z), (x + s / 2, y + s / 2, z + s), wood,
              rot_z_deg=10.0 * k)
    H.box("van", (4.0, 9.0, 0.0), (9.0, 11.0, 2.2), white, rot_z_deg=25.0)
    for k in range(4):
        x = -3.0 + 1.9 * k
        H.box("barrier_%d" % k, (x, 4.0, 0.0), (x + 1.8, 4.4, 0.8), concrete)

    H.world(scene, (0.45, 0.60, 0.90), strength=1.2)
    H.sun("sun", (0.55, 0.45, -0.70), strength=4.0, angle_deg=1.0)

    cam = H.camera("Camera", lens_mm=28.0)
    p1, p4 = (-1.0, -7.0, 1.7), (-0.4, -6.8, 1.7)
    H.key_aimed(cam, 1, p1, (-0.5, 12.0, 1.6))
    H.key_aimed(cam, 4, p4, (1.0, 12.0, 1.6))
    H.smooth_fcurves(cam, 'BEZIER')


if __name__ == "__main__":
    H.run("yard", build)
