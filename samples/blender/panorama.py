"""Render a panoramic G-buffer of the open Blender scene for hbil's radiance cache.

    blender -b shot.blend --python samples/blender/panorama.py -- \
        --out DIR [--size 128x64] [--samples 4] [--frames 1-8]

For each frame, an equirectangular view from the scene camera's position (Cycles' panoramic
camera, the whole sphere) is rendered to DIR/pano_####.exr with the passes hbil's
`panorama` key reads: Position (world), DiffCol, DiffDir, Emit, and Depth (the background:
1e10). Direct light only (no bounces are needed: DiffDir is direct light), no Combined
beyond what Blender always writes. The scene's own camera, resolution and passes are put
back afterwards, so the script can run before or after the main render of the same file.
hbil maps what the panorama sees outside the frame around the camera and lights the
gather's empty directions with it (man hbil, radiance_cache and panorama).
"""
import argparse
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import export_camera  # noqa: E402


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser()
    p.add_argument("--out", required=True)
    p.add_argument("--size", default="128x64", help="WxH of the equirectangular image")
    p.add_argument("--samples", type=int, default=4)
    p.add_argument("--frames", default=None, help="A-B (default: the scene's range)")
    a = p.parse_args(argv)
    w, h = (int(v) for v in a.size.lower().split("x"))
    if w < 8 or h < 4:
        raise SystemExit("--size must be at least 8x4")
    scene = bpy.context.scene
    if scene.camera is None:
        raise SystemExit("the scene has no camera")
    frames = export_camera.parse_frames(a.frames or "%d-%d" % (scene.frame_start,
                                                                scene.frame_end))
    cam = scene.camera.data
    r, c, vl = scene.render, scene.cycles, bpy.context.view_layer
    saved = dict(type=cam.type, pano=cam.cycles.panorama_type, size=(r.resolution_x,
                 r.resolution_y, r.resolution_percentage), samples=c.samples,
                 bounces=(c.max_bounces, c.diffuse_bounces), engine=r.engine,
                 fmt=r.image_settings.file_format, path=r.filepath,
                 passes={k: getattr(vl, k) for k in (
                     "use_pass_z", "use_pass_position", "use_pass_diffuse_color",
                     "use_pass_diffuse_direct", "use_pass_emit", "use_pass_normal",
                     "use_pass_vector", "use_pass_diffuse_indirect", "use_pass_environment",
                     "use_pass_ambient_occlusion")})
    try:
        r.engine = 'CYCLES'
        cam.type = 'PANO'
        cam.cycles.panorama_type = 'EQUIRECTANGULAR'
        r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
        c.samples = a.samples
        c.max_bounces = c.diffuse_bounces = 0
        r.image_settings.file_format = 'OPEN_EXR_MULTILAYER'
        r.image_settings.color_depth = '32'
        for k in saved["passes"]:
            setattr(vl, k, k in ("use_pass_z", "use_pass_position", "use_pass_diffuse_color",
                                 "use_pass_diffuse_direct", "use_pass_emit"))
        out = os.path.abspath(a.out)
        os.makedirs(out, exist_ok=True)
        for f in frames:
            scene.frame_set(f)
            r.filepath = os.path.join(out, "pano_%04d.exr" % f)
            t0 = time.time()
            bpy.ops.render.render(write_still=True)
            print("HBIL_PANORAMA frame=%d seconds=%.2f file=%s"
                  % (f, time.time() - t0, r.filepath), flush=True)
    finally:
        cam.type, cam.cycles.panorama_type = saved["type"], saved["pano"]
        r.resolution_x, r.resolution_y, r.resolution_percentage = saved["size"]
        c.samples = saved["samples"]
        c.max_bounces, c.diffuse_bounces = saved["bounces"]
        r.engine, r.image_settings.file_format = saved["engine"], saved["fmt"]
        r.filepath = saved["path"]
        for k, v in saved["passes"].items():
            setattr(vl, k, v)


main()
