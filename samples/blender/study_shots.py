"""The held-out "study" room (study.py) with camera moves nothing was tuned on, for the
temporal chain's "never seen" check (README "Temporal chain").

    blender -b --factory-startup --python samples/blender/study_shots.py -- \
        --shot move --out /tmp/study_move --mode main --samples 128 --frames 1-16
    blender -b --factory-startup --python samples/blender/study_shots.py -- \
        --shot cut --out /tmp/study_cut --mode main --samples 128 --frames 1-12
    blender -b --factory-startup --python samples/blender/study_shots.py -- \
        --shot long --out /tmp/study_long --mode main --samples 16 --frames 1-64

move: 16 frames walking from the front right corner (looking at the bookcase) to the front
      left (looking at the lamp): 3.2 m and an 84 degree pan.
cut:  frames 1-6 drift slowly at the open front; frame 7 cuts to the window corner looking
      back at the table and the blue wall, frames 7-12 drift slowly there.
long: 64 frames of the move's walk, four times slower (5 cm and 1.3 degrees a frame), for
      farm chunks and their seams (README "On the farm").
Not committed (like study.py); add --mode backfaces renders and merge_backdepth.py as for the
samples.
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hbil_common as H  # noqa: E402
import study  # noqa: E402

SHOT = H.pop_choice("--shot", ("move", "cut", "long"))


def pose(cam, frame, loc, yaw, pitch=76.0):
    H.key(cam, frame, location=loc,
          rotation_euler=(math.radians(pitch), 0.0, math.radians(yaw)))


def build(scene):
    study.build(scene)
    cam = scene.camera
    cam.animation_data_clear()
    if SHOT in ("move", "long"):
        pose(cam, 1, (2.0, -1.5, 1.5), 38.0)
        pose(cam, 16 if SHOT == "move" else 64, (-1.2, -1.6, 1.6), -46.0)
        H.smooth_fcurves(cam, 'BEZIER')
        return
    pose(cam, 1, (1.6, -2.6, 1.55), 22.0)
    pose(cam, 6, (1.2, -2.5, 1.50), 16.0)
    pose(cam, 7, (-2.0, 1.5, 1.70), -123.0, 74.0)
    pose(cam, 12, (-1.9, 1.3, 1.65), -120.0, 74.0)
    H.hard_cut(cam, 6)  # frame 6's pose holds until the jump at frame 7


if __name__ == "__main__":
    H.run("study_" + SHOT, build)
