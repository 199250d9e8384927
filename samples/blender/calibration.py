"""Render the calibration frames of the open Blender scene, where hbil finds them.

    blender -b shot.blend --python samples/blender/calibration.py -- \
        --output //render/frame_####.exr [--every 4] [--width 256] [--samples 1] [--frames A-B]

A calibration frame is the scene rendered again with global illumination, small and at one
sample per pixel, with the Diffuse Color and Diffuse Indirect passes: its mean tells hbil the
level of the light that the frame does not show, and its tiles where that light is (man hbil,
`calibration`). ``--output`` is the pattern of the shot's own frames, as for
export_camera.py; each render goes to a folder ``calibration`` beside them under the frame's
own name (``//render/calibration/frame_0001.exr``), where hbil's default (`calibration`
"auto") finds it.

Frames: the first of the range (``--frames``, default the scene's), every N-th after it
(``--every``, default 4; 0: the first alone) and the last. Size: ``--width`` pixels (default
256; never more than the scene's), the height in the scene's aspect. Cycles, ``--samples``
(default 1) without adaptive sampling or denoising, the scene's own bounces and seed (its
global illumination is what hbil stands in for). The scene's settings are put back
afterwards, so the script can run before or after the main render of the same file.
"""
import argparse
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import export_camera  # noqa: E402

PASSES = ("use_pass_diffuse_color", "use_pass_diffuse_indirect")


def calibration_frames(frames, every):
    """The first frame, every `every`-th after it and the last: [1..20], 8 -> 1, 9, 17, 20."""
    if not frames:
        return []
    picked = frames[::every] if every > 0 else frames[:1]
    if every > 0 and picked[-1] != frames[-1]:
        picked.append(frames[-1])
    return picked


def calibration_path(pattern, frame):
    """The frame's own file name in calibration/ beside it."""
    path = export_camera.frame_image_path(pattern, frame)
    return os.path.join(os.path.dirname(path), "calibration", os.path.basename(path))


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender -b shot.blend --python calibration.py --")
    p.add_argument("--output", required=True,
                   help="the shot's frame pattern, e.g. //render/frame_####.exr")
    p.add_argument("--frames", default=None, help="A-B (default: the scene's range)")
    p.add_argument("--every", type=int, default=4)
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--samples", type=int, default=1)
    a = p.parse_args(argv)
    if a.every < 0 or a.width < 16 or a.samples < 1:
        raise SystemExit("--every must be >= 0, --width >= 16 and --samples >= 1")
    scene = bpy.context.scene
    if scene.camera is None:
        raise SystemExit("the scene has no camera")
    frames = export_camera.parse_frames(a.frames or "%d-%d" % (scene.frame_start,
                                                                scene.frame_end))
    r, c, vl = scene.render, scene.cycles, bpy.context.view_layer
    full_w = r.resolution_x * r.resolution_percentage / 100.0
    full_h = r.resolution_y * r.resolution_percentage / 100.0
    w = int(min(a.width, full_w))
    h = max(1, int(round(w * full_h / full_w)))
    saved = dict(size=(r.resolution_x, r.resolution_y, r.resolution_percentage),
                 samples=c.samples, adaptive=c.use_adaptive_sampling,
                 denoise=c.use_denoising, engine=r.engine,
                 fmt=(r.image_settings.file_format, r.image_settings.color_depth),
                 path=r.filepath, passes={k: getattr(vl, k) for k in PASSES},
                 layers={o.name: o.use for o in scene.view_layers})
    try:
        r.engine = 'CYCLES'
        r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
        c.samples = a.samples
        c.use_adaptive_sampling = False
        c.use_denoising = False
        r.image_settings.file_format = 'OPEN_EXR_MULTILAYER'
        r.image_settings.color_depth = '32'
        for k in PASSES:
            setattr(vl, k, True)
        for o in scene.view_layers:  # the active layer alone (not BackFaces and the like)
            o.use = o.name == vl.name
        for f in calibration_frames(frames, a.every):
            scene.frame_set(f)
            r.filepath = calibration_path(a.output, f)
            os.makedirs(os.path.dirname(r.filepath), exist_ok=True)
            t0 = time.time()
            bpy.ops.render.render(write_still=True)
            print("HBIL_CALIBRATION frame=%d seconds=%.2f file=%s"
                  % (f, time.time() - t0, r.filepath), flush=True)
    finally:
        r.resolution_x, r.resolution_y, r.resolution_percentage = saved["size"]
        c.samples = saved["samples"]
        c.use_adaptive_sampling, c.use_denoising = saved["adaptive"], saved["denoise"]
        r.engine = saved["engine"]
        r.image_settings.file_format, r.image_settings.color_depth = saved["fmt"]
        r.filepath = saved["path"]
        for k, v in saved["passes"].items():
            setattr(vl, k, v)
        for name, use in saved["layers"].items():
            scene.view_layers[name].use = use


main()
