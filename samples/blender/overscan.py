"""Render the open Blender scene with a guard band around its framing, for hbil.

    blender -b shot.blend --python samples/blender/overscan.py -- \
        --percent 10 --out DIR [--frames 1-8]

Renders each frame P % larger on every side (the sensor grows with the resolution, so the
focal length in pixels and the framing stay), writes DIR/frame_####.exr with the original
frame as its display window and the guard band in its data window (origin (-gx, -gy)), and a
camera sidecar for the display window beside it (export_camera.py). hbil searches and
gathers from the guard band, writes its outputs over the whole data window and frames its
display images on the display window (man hbil, "Data and display windows"). The scene's
own settings (passes, samples, output format: multilayer EXR) are used as they are; the
camera must be landscape, sensor fit AUTO, without shift. The scene scripts of this folder
take the same guard band as `--overscan P`.
"""
import argparse
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import export_camera  # noqa: E402
import hbil_common  # noqa: E402


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser()
    p.add_argument("--percent", type=float, required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--frames", default=None, help="A-B (default: the scene's range)")
    a = p.parse_args(argv)
    if not a.percent > 0:
        raise SystemExit("--percent must be > 0")
    scene = bpy.context.scene
    if scene.render.image_settings.file_format != 'OPEN_EXR_MULTILAYER':
        raise SystemExit("the scene must render multilayer EXR (Output Properties)")
    frames = export_camera.parse_frames(a.frames or "%d-%d" % (scene.frame_start,
                                                                scene.frame_end))
    overscan = hbil_common.Overscan(scene, a.percent)
    overscan.grow(scene)
    try:
        hbil_common.render_frames(scene, a.out, frames, overscan)
    finally:
        overscan.original(scene)


main()
