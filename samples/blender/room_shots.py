"""room_poles with other camera work, for the temporal chain's stability measurements.

    blender -b --factory-startup --python samples/blender/room_shots.py -- \
        --shot static --out samples/room_static --mode main --samples 256 --frames 1-6
    blender -b --factory-startup --python samples/blender/room_shots.py -- \
        --shot cut --out samples/room_cut --mode main --samples 256 --frames 1-6
    blender -b --factory-startup --python samples/blender/room_shots.py -- \
        --shot long --out /tmp/room_long --mode main --samples 16 --frames 1-64

static: the camera holds room_poles' frame-1 pose on every frame (with the fixed seed the
        Cycles frames are identical, so any change between hbil's frames is its own flicker).
cut:    frames 1-3 dolly slowly as in room_poles; frame 4 cuts hard to the opposite corner,
        looking back at the window wall, and frames 4-6 dolly slowly there.
long:   64 frames dollying and panning slowly from room_poles' frame-1 pose towards the
        poles (1.6 cm and 0.5 degrees a frame), for farm chunks and their seams.
pan:    12 frames panning 10 degrees a frame from the window wall, whose sunlit floor patch
        fills frame 1, to the green wall, which the patch lights from off screen (the
        radiance cache's measurements).
Same scene, lights and render settings as room_poles.py (hbil_common.py).
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402
import room_poles  # noqa: E402

SHOT = H.pop_choice("--shot", ("static", "cut", "long", "pan"))


def build(scene):
    room_poles.build(scene)
    cam = scene.camera
    cam.animation_data_clear()
    a = dict(location=(0.70, -1.90, 1.60),
             rotation_euler=(math.radians(74.0), 0.0, math.radians(16.0)))
    if SHOT == "static":
        H.key(cam, 1, **a)
        return
    if SHOT == "pan":
        H.key(cam, 1, location=(0.60, -1.50, 1.50),
              rotation_euler=(math.radians(70.0), 0.0, math.radians(60.0)))
        H.key(cam, 12, location=(0.60, -1.50, 1.50),
              rotation_euler=(math.radians(70.0), 0.0, math.radians(-50.0)))
        for fc in cam.animation_data.action.fcurves:
            for k in fc.keyframe_points:
                k.interpolation = "LINEAR"
        return
    if SHOT == "long":
        H.key(cam, 1, **a)
        H.key(cam, 64, location=(-0.30, -1.60, 1.55),
              rotation_euler=(math.radians(75.0), 0.0, math.radians(-16.0)))
        return
    H.key(cam, 1, **a)
    H.key(cam, 3, location=(0.60, -1.80, 1.60),
          rotation_euler=(math.radians(74.0), 0.0, math.radians(14.0)))
    # The cut: another corner of the room, looking back towards the window wall.
    H.key(cam, 4, location=(1.70, 1.20, 1.70),
          rotation_euler=(math.radians(72.0), 0.0, math.radians(105.0)))
    H.key(cam, 6, location=(1.55, 1.05, 1.65),
          rotation_euler=(math.radians(73.0), 0.0, math.radians(108.0)))
    H.hard_cut(cam, 3)  # frame 3's pose holds until the jump at frame 4


if __name__ == "__main__":
    H.run("room_" + SHOT, build)
