"""hbil held-out scene "street": a street canyon tens of metres across.

    blender -b --factory-startup --python samples/blender/street.py -- \
        --out /tmp/scenes/street --mode main --samples 128 --seed 1 --frames 1-4

A 30 m long, 8 m wide street (x in [-4, 4], y in [0, 30]): a dark asphalt
road with two 2 m sidewalks (0.15 m kerb), lined on both sides by building
facades 10-12 m high in segments of 4-8 m with varied albedos.  The facades
have recessed bays (set back 1 m), 1.2 m deep balcony slabs (0.2 m) with 1 m
parapets, and a 3 m side street on the left through which the sun falls onto
the road; a building closes the view at y = 44 m.  Four parked cars are
boxes of about 4 x 1.8 x 1.5 m (body and cabin).  The sun is low from the
left (about 38 degrees up): it lights the upper part of the right facades,
which bounce onto the shadowed left facades and the street.  The camera
stands at 1.7 m on the road near y = -2 m, looking down the street (objects
from 3 to 45 m away), and creeps forward and right over frames 1-4.
A held-out validation scene for the automatic gather radius / thickness
defaults (scene scale: metres to tens of metres); it is not test data.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402


def build(scene):
    asphalt = H.diffuse("asphalt", (0.10, 0.10, 0.11))
    pave = H.diffuse("pavement", (0.45, 0.43, 0.40))
    fac = [H.diffuse("facade_cream", (0.78, 0.70, 0.55)),
           H.diffuse("facade_ochre", (0.75, 0.50, 0.20)),
           H.diffuse("facade_grey", (0.50, 0.50, 0.52)),
           H.diffuse("facade_brick", (0.55, 0.22, 0.14)),
           H.diffuse("facade_white", (0.85, 0.85, 0.82)),
           H.diffuse("facade_green", (0.30, 0.50, 0.35))]
    slab = H.diffuse("concrete", (0.62, 0.60, 0.56))
    cars = [H.diffuse("car_red", (0.70, 0.08, 0.06)),
            H.diffuse("car_blue", (0.10, 0.20, 0.60)),
            H.diffuse("car_white", (0.80, 0.80, 0.80)),
            H.diffuse("car_dark", (0.15, 0.15, 0.15))]

    Y0, Y1 = -10.0, 40.0  # the ground runs past the 30 m street at both ends
    H.box("road", (-4.0, Y0, -0.2), (4.0, Y1, 0.0), asphalt)
    H.box("sidewalk_l", (-6.0, Y0, -0.2), (-2.0, Y1, 0.15), pave)
    H.box("sidewalk_r", (2.0, Y0, -0.2), (6.0, Y1, 0.15), pave)
    H.box("side_street", (-30.0, 13.0, -0.2), (-6.0, 16.0, 0.0), asphalt)

    # building segments (y0, y1, height, material index, recessed)
    left = [(-10, -2, 11.0, 0, False), (-2, 4, 12.0, 3, False), (4, 9, 10.0, 1, True),
            (9, 13, 11.5, 2, False), (16, 22, 10.5, 4, False), (22, 26, 12.0, 5, True),
            (26, 40, 11.0, 3, False)]
    right = [(-10, -1, 10.5, 2, False), (-1, 6, 11.5, 4, False), (6, 10, 12.0, 0, True),
             (10, 17, 10.0, 3, False), (17, 21, 11.0, 1, True), (21, 28, 12.0, 5, False),
             (28, 40, 10.5, 0, False)]
    for side, segs in (("l", left), ("r", right)):
        s = -1.0 if side == "l" else 1.0
        for i, (y0, y1, h, m, recess) in enumerate(segs):
            face = 4.0 + (1.0 if recess else 0.0)  # distance of the facade from the axis
            x_in, x_out = s * face, s * 14.0
            H.box("bldg_%s%d" % (side, i), (min(x_in, x_out), y0, 0.0),
                  (max(x_in, x_out), y1, h), fac[m])
            if recess:
                # piers at both ends of the recessed bay, flush with the street line
                for j, (a, b) in enumerate(((y0, y0 + 0.6), (y1 - 0.6, y1))):
                    H.box("pier_%s%d_%d" % (side, i, j), (min(s * 4.0, s * 5.0), a, 0.0),
                          (max(s * 4.0, s * 5.0), b, h), fac[m])
            elif y1 - y0 >= 5 and -5 < y0 < 30:
                # balconies on floors 2-3: slab + parapet
                for k, z in enumerate((3.5, 6.5)):
                    xa, xb = s * 4.0, s * 2.8
                    ya, yb = y0 + 1.0, y1 - 1.0
                    H.box("balc_%s%d_%d" % (side, i, k), (min(xa, xb), ya, z),
                          (max(xa, xb), yb, z + 0.2), slab)
                    xp = s * 2.8
                    H.box("parapet_%s%d_%d" % (side, i, k),
                          (min(xp, xp + s * 0.12), ya, z + 0.2),
                          (max(xp, xp + s * 0.12), yb, z + 1.2), slab)
    H.box("bldg_end", (-14.0, 44.0, 0.0), (14.0, 50.0, 14.0), fac[1])

    # parked cars: 4 x 1.8 m, body 0.85 m + cabin 0.65 m = 1.5 m
    for i, (x, y, m) in enumerate([(-3.0, 6.0, 0), (-3.0, 11.5, 1), (3.0, 3.0, 2),
                                   (3.0, 18.0, 3)]):
        H.box("car_%d" % i, (x - 0.9, y - 2.0, 0.0), (x + 0.9, y + 2.0, 0.85), cars[m])
        H.box("cabin_%d" % i, (x - 0.8, y - 1.1, 0.85), (x + 0.8, y + 0.9, 1.5), cars[m])

    H.world(scene, (0.35, 0.45, 0.65), strength=0.8)
    H.sun("sun", (0.72, 0.30, -0.62), strength=4.0, angle_deg=1.0)

    cam = H.camera("Camera", lens_mm=24.0)
    p1, p4 = (-0.6, -2.0, 1.7), (0.2, -0.8, 1.7)
    H.key_aimed(cam, 1, p1, (0.6, 30.0, 4.0))
    H.key_aimed(cam, 4, p4, (0.0, 30.0, 4.2))
    H.smooth_fcurves(cam, 'BEZIER')


if __name__ == "__main__":
    H.run("street", build)
