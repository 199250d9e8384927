"""Write hbil camera sidecars (``X.camera.json``) next to rendered frames ``X.exr``.

hbil reads the camera of every frame from a small JSON file that sits next to
the multilayer EXR.  Blender's EXR header carries no camera matrices, so this
script writes them out of the .blend.

Usage
-----
1. Add sidecars to a sequence that is already rendered (no render happens)::

       blender -b file.blend --python samples/blender/export_camera.py -- \
           --output //render/frame_####.exr --frames 1-8

   ``--output`` is the frame path pattern (Blender style: ``//`` is relative to
   the .blend, the last run of ``#`` is the zero-padded frame number; without
   ``#`` a 4-digit number is appended).  The extension is replaced by
   ``.camera.json``.  Without ``--output`` the scene's own output path
   (Output Properties) is used.  ``--frames`` takes ``1-8``, ``1,3,5-7`` or a
   single number; default: the scene's frame range.  ``--scene NAME`` picks a
   scene other than the active one.

2. Write sidecars while Blender renders an animation (handlers)::

       blender -b file.blend --python samples/blender/export_camera.py -a -- --register

   (``-a`` must come before ``--``).  Running the script with no arguments
   after ``--`` (or from the Text Editor) also just registers the handlers;
   every frame Blender writes to disk then gets its sidecar.

3. From another script (what samples/blender/*.py do)::

       import export_camera
       export_camera.write_sidecar(scene, exr_path, frame, depsgraph)
       # or: export_camera.register()

Format (``"format": "hbil-camera-1"``)::

    {"format": "hbil-camera-1", "source": "blender", "frame": 3,
     "resolution": [256, 144],        # rendered pixels, resolution_percentage applied
     "pixel_aspect": 1.0,             # pixel_aspect_y / pixel_aspect_x
     "type": "PERSP",                 # camera data type (PERSP, ORTHO, PANO)
     "matrix_world": [[...4], [...4], [...4], [0, 0, 0, 1]],
                                      # camera -> world, row-major rows, Blender
                                      # convention: camera looks down -Z, +Y up
     "lens_mm": 50.0, "sensor_width_mm": 36.0, "sensor_height_mm": 24.0,
     "sensor_fit": "AUTO", "shift_x": 0.0, "shift_y": 0.0,
     "clip_start": 0.1, "clip_end": 100.0}

The camera is ``scene.camera`` evaluated by the depsgraph at that frame, so
animation, constraints and parenting are included.

Pinhole model for PERSP with sensor_fit AUTO and width*pixel_aspect_x >=
height*pixel_aspect_y (the usual landscape case):
focal_px = lens_mm / sensor_width_mm * width;
principal point (raster, y up) = (width/2 + shift_x*max(w,h), height/2 + shift_y*max(w,h)).
EXR rows run top-down, so row = height - y_up.
"""

import json
import os
import re
import struct
import sys

import bpy

FORMAT = "hbil-camera-1"


# --------------------------------------------------------------------------- #
# core
# --------------------------------------------------------------------------- #
def render_resolution(scene):
    """Pixels Blender really renders (same integer maths as BKE_render_resolution)."""
    r = scene.render
    return [int(r.resolution_x * r.resolution_percentage // 100),
            int(r.resolution_y * r.resolution_percentage // 100)]


def camera_record(scene, frame, depsgraph=None):
    """Return the sidecar dict for ``scene.camera`` at the current evaluation state.

    ``depsgraph``: the depsgraph evaluated at ``frame`` (None: the context's).
    The caller is responsible for the scene being at ``frame``.
    """
    cam = scene.camera
    if cam is None:
        raise RuntimeError("scene %r has no active camera" % scene.name)
    if depsgraph is None:
        depsgraph = bpy.context.evaluated_depsgraph_get()
    cam_eval = cam.evaluated_get(depsgraph)
    m = cam_eval.matrix_world
    data = cam_eval.data
    r = scene.render
    return {
        "format": FORMAT,
        "source": "blender",
        "frame": int(frame),
        "resolution": render_resolution(scene),
        "pixel_aspect": float(r.pixel_aspect_y) / float(r.pixel_aspect_x),
        "type": str(data.type),
        "matrix_world": [[float(m[i][j]) for j in range(4)] for i in range(4)],
        "lens_mm": float(data.lens),
        "sensor_width_mm": float(data.sensor_width),
        "sensor_height_mm": float(data.sensor_height),
        "sensor_fit": str(data.sensor_fit),
        "shift_x": float(data.shift_x),
        "shift_y": float(data.shift_y),
        "clip_start": float(data.clip_start),
        "clip_end": float(data.clip_end),
    }


def sidecar_path(image_path):
    """``/a/frame_0003.exr`` -> ``/a/frame_0003.camera.json``."""
    root, ext = os.path.splitext(image_path)
    if ext.lower() not in (".exr", ".png", ".tif", ".tiff", ".jpg", ".jpeg", ".hdr", ".dpx"):
        root = image_path
    return root + ".camera.json"


def _f32(v):
    """Shortest decimal that reads back as the same float32 (Blender stores float32)."""
    v = float(v)
    want = struct.pack("<f", v)
    for p in range(6, 10):
        s = float("%.*g" % (p, v))
        if struct.pack("<f", s) == want:
            return s + 0.0  # no -0.0
    return v


def dumps(record):
    """JSON text, one key per line, matrix rows on one line each."""
    lines = []
    for k, v in record.items():
        if k == "matrix_world":
            rows = ",\n    ".join(json.dumps([_f32(x) for x in row]) for row in v)
            lines.append('  "%s": [\n    %s\n  ]' % (k, rows))
        elif isinstance(v, float):
            lines.append("  %s: %s" % (json.dumps(k), json.dumps(_f32(v))))
        else:
            lines.append("  %s: %s" % (json.dumps(k), json.dumps(v)))
    return "{\n" + ",\n".join(lines) + "\n}\n"


def write_record(record, image_path):
    path = sidecar_path(image_path)
    d = os.path.dirname(path)
    if d:
        os.makedirs(d, exist_ok=True)
    tmp = path + ".tmp"
    text = dumps(record)
    json.loads(text)  # self-check
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)
    return path


def write_sidecar(scene, image_path, frame=None, depsgraph=None):
    """Write the sidecar for ``image_path``; the scene must already be at ``frame``."""
    if frame is None:
        frame = scene.frame_current
    return write_record(camera_record(scene, frame, depsgraph), image_path)


def frame_image_path(pattern, frame):
    """Blender-style frame path: ``//`` relative to the .blend, last ``#`` run = frame."""
    path = bpy.path.abspath(pattern)
    runs = list(re.finditer(r"#+", path))
    if runs:
        m = runs[-1]
        path = path[:m.start()] + str(frame).zfill(len(m.group(0))) + path[m.end():]
    else:
        root, ext = os.path.splitext(path)
        if ext.lower() == ".exr":
            path = root + "%04d" % frame + ext
        else:
            path = path + "%04d" % frame
    return os.path.abspath(path)


# --------------------------------------------------------------------------- #
# handlers: record camera on frame change (render depsgraph), write on render_write
# --------------------------------------------------------------------------- #
_pending = {}


def _on_frame_change_post(scene, depsgraph=None):
    # Only remember; writing here would litter files while scrubbing in the UI.
    try:
        _pending[(scene.name, scene.frame_current)] = camera_record(
            scene, scene.frame_current, depsgraph)
    except Exception as e:  # never break the render because of the sidecar
        print("export_camera: frame_change_post failed: %s" % e)


def _on_render_write(scene, *args):
    frame = scene.frame_current
    try:
        rec = _pending.pop((scene.name, frame), None)
        if rec is None:
            rec = camera_record(scene, frame, None)
        path = write_record(rec, scene.render.frame_path(frame=frame))
        print("export_camera: wrote %s" % path)
    except Exception as e:
        print("export_camera: render_write failed: %s" % e)


def register():
    unregister()
    bpy.app.handlers.frame_change_post.append(_on_frame_change_post)
    bpy.app.handlers.render_write.append(_on_render_write)


def unregister():
    for lst, fn in ((bpy.app.handlers.frame_change_post, _on_frame_change_post),
                    (bpy.app.handlers.render_write, _on_render_write)):
        for h in list(lst):
            if getattr(h, "__name__", "") == fn.__name__ and \
                    getattr(h, "__module__", "") == fn.__module__:
                lst.remove(h)


# --------------------------------------------------------------------------- #
# command line
# --------------------------------------------------------------------------- #
def parse_frames(text):
    frames = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        m = re.fullmatch(r"(-?\d+)\s*(?:-|\.\.)\s*(-?\d+)", part)
        if m:
            a, b = int(m.group(1)), int(m.group(2))
            frames.extend(range(a, b + 1) if a <= b else range(a, b - 1, -1))
        else:
            frames.append(int(part))
    return frames


def main(argv):
    import argparse
    p = argparse.ArgumentParser(
        prog="blender -b file.blend --python export_camera.py --",
        description="Write hbil-camera-1 JSON sidecars next to rendered frames.")
    p.add_argument("--output", help="frame path pattern, e.g. //render/frame_####.exr "
                   "(default: the scene's output path)")
    p.add_argument("--frames", help="e.g. 1-8 or 1,3,5-7 (default: scene frame range)")
    p.add_argument("--scene", help="scene name (default: active scene)")
    p.add_argument("--register", action="store_true",
                   help="only register render handlers (use with -a before --)")
    a = p.parse_args(argv)

    if a.register or (a.output is None and a.frames is None):
        register()
        print("export_camera: handlers registered; sidecars are written as frames render")
        return

    scene = bpy.data.scenes[a.scene] if a.scene else bpy.context.scene
    frames = parse_frames(a.frames) if a.frames else \
        list(range(scene.frame_start, scene.frame_end + 1, scene.frame_step))
    pattern = a.output if a.output else scene.render.filepath
    keep = scene.frame_current
    for f in frames:
        scene.frame_set(f)  # evaluates the depsgraphs of all the scene's view layers
        if scene == bpy.context.scene:
            dg = bpy.context.evaluated_depsgraph_get()
        else:
            dg = scene.view_layers[0].depsgraph
        if a.output:
            img = frame_image_path(pattern, f)
        else:
            img = scene.render.frame_path(frame=f)
        print("export_camera: wrote %s" % write_sidecar(scene, img, f, dg))
    scene.frame_set(keep)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
