"""Make the tiny Cycles renders that tests/camera_io_test.cpp checks cameras against.

    blender -b --factory-startup --python tests/data/camera/make.py

Writes, next to this script, for each case below: <case>.exr (multilayer EXR, 32-bit
float, ZIP, passes Depth and Position only) and <case>.camera.json (the sidecar, written by
samples/blender/export_camera.py). The scene: three cubes on a ground plane, so that the
Position pixels are far from coplanar. The cameras use non-zero lens shift, non-square
resolutions, sensor_fit AUTO (landscape and portrait) and VERTICAL, and a non-square pixel
aspect, to pin down Blender's projection rules (signs of shift_x / shift_y, which sensor
size is used, how pixel aspect scales fy).
"""

import os
import sys

import bpy
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "samples", "blender"))
import export_camera  # noqa: E402

# name: (resolution, pixel_aspect_x, pixel_aspect_y, lens, sensor w, h, fit, shift x, y)
CASES = {
    "auto_wide": ((64, 48), 1.0, 1.0, 35.0, 36.0, 24.0, "AUTO", 0.15, -0.10),
    "vertical": ((56, 40), 1.0, 1.0, 28.0, 36.0, 20.0, "VERTICAL", -0.12, 0.08),
    "auto_tall_aspect": ((40, 56), 1.0, 1.25, 40.0, 32.0, 24.0, "AUTO", 0.10, 0.20),
}


def build_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = 'CYCLES'
    sc.cycles.device = 'CPU'
    sc.cycles.samples = 4
    sc.cycles.use_denoising = False
    sc.render.resolution_percentage = 100
    sc.render.use_stamp = False
    vl = sc.view_layers[0]
    vl.use_pass_combined = False
    vl.use_pass_z = True
    vl.use_pass_position = True
    s = sc.render.image_settings
    s.file_format = 'OPEN_EXR_MULTILAYER'
    s.color_depth = '32'
    s.exr_codec = 'ZIP'
    for loc, size in [((0, 0, 0.5), 1.0), ((1.5, 0.8, 0.35), 0.7), ((-1.2, 1.0, 0.6), 1.2)]:
        bpy.ops.mesh.primitive_cube_add(size=size, location=loc)
    bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, -0.01))
    cd = bpy.data.cameras.new("Cam")
    cam = bpy.data.objects.new("Cam", cd)
    sc.collection.objects.link(cam)
    sc.camera = cam
    cam.location = (5.0, -4.0, 3.0)
    cam.rotation_euler = (Vector((0, 0, 0.4)) - cam.location).to_track_quat('-Z', 'Y').to_euler()
    cam.rotation_euler.y += 0.05  # a little roll
    return sc, cam


def main():
    sc, cam = build_scene()
    for name, (res, pax, pay, lens, sw, sh, fit, shx, shy) in CASES.items():
        sc.render.resolution_x, sc.render.resolution_y = res
        sc.render.pixel_aspect_x, sc.render.pixel_aspect_y = pax, pay
        cd = cam.data
        cd.lens, cd.sensor_width, cd.sensor_height, cd.sensor_fit = lens, sw, sh, fit
        cd.shift_x, cd.shift_y = shx, shy
        sc.frame_set(1)
        exr = os.path.join(HERE, name + ".exr")
        sc.render.filepath = exr
        bpy.ops.render.render(write_still=True)
        export_camera.write_sidecar(sc, exr, 1, bpy.context.evaluated_depsgraph_get())


main()
