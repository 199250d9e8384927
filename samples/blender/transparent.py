"""hbil test scene "transparent": a film-transparent render, for the composite's alpha.

    blender -b --factory-startup --python samples/blender/transparent.py -- \
        --out tests/data/transparent --mode main --samples 16 --seed 1 --frames 1-1 --size 64x36

Three objects floating in front of nothing: a sphere, a cube resting on a small slab, and
a thin tilted panel, lit by a sun and a dim world. Rendered with Film > Transparent, so
Combined's alpha is 0 where the world shows, 1 on the objects and fractional along their
edges (the pixel filter), and Combined's colour is premultiplied by it. The display image
of the composite must hold straight colour there (tests/display_test.cpp).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def build(scene):
    red = H.diffuse("red", (0.75, 0.12, 0.08))
    white = H.diffuse("white", (0.8, 0.8, 0.8))
    blue = H.diffuse("blue", (0.1, 0.25, 0.7))
    H.sphere("sphere", (-0.7, 0.0, 0.5), 0.5, red)
    H.box("slab", (0.0, -0.5, -0.1), (1.2, 0.5, 0.0), white)
    H.box("cube", (0.3, -0.25, 0.0), (0.8, 0.25, 0.5), blue, rot_z_deg=20.0)
    H.box("panel", (-0.2, 0.6, 0.0), (0.6, 0.63, 0.9), white, rot_z_deg=-15.0)
    H.world(scene, (0.3, 0.35, 0.45), strength=0.5)
    H.sun("sun", (0.4, 0.6, -0.7), 3.0)
    cam = H.camera("Camera", lens_mm=35.0)
    H.key_aimed(cam, 1, (0.3, -4.0, 1.6), (0.0, 0.1, 0.35))


if __name__ == "__main__":
    H.run("transparent", build, film_transparent=True)
