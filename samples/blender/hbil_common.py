"""Shared helpers for the hbil sample scenes (room_poles.py, courtyard.py).

Builds geometry with plain diffuse / emission materials, configures Cycles and
the view-layer passes, renders a frame range one frame at a time and writes the
camera sidecar next to every frame (export_camera.py).

Command line common to all scene scripts (after ``--``)::

    --out DIR          output folder; frames go to DIR/frame_####.exr
    --mode main|bounce1
                       main:    8 diffuse bounces, all passes (Combined, Depth, Normal,
                                Position, Vector, DiffCol/Dir/Ind, Emit, Env, AO)
                       bounce1: 1 diffuse bounce, DiffCol/Dir/Ind + Depth only
    --mode backfaces   only the BackFaces view layer (backfaces.py): the depth of the
                       first back face, 1 sample; merge_backdepth.py adds it to main frames
    --samples N        Cycles samples per pixel (fixed, no adaptive sampling)
    --size WxH         render resolution in pixels (default 256x144; the committed samples
                       use the default). The camera sidecar records the size rendered.
    --bounces N        override the mode's bounce count (max_bounces = diffuse_bounces = N);
                       0 = direct light only. Default: the mode's own (main 8, bounce1 1).
    --overscan P       render P % more on each side (the focal length in pixels and the
                       framing kept), and write each EXR with the original frame as its display
                       window and the guard band beyond it in the data window (origin
                       (-gx, -gy)); the sidecar describes the display window (hbil reads it so)
    --seed S           Cycles seed (fixed for all frames)
    --frames 1-8       frames to render
    --save-blend PATH  also save the built scene
    --no-render        build (and save) only
"""

import argparse
import math
import os
import sys
import time

import bpy
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import export_camera  # noqa: E402

RES = (256, 144)  # default --size
FRAMES = (1, 8)


# --------------------------------------------------------------------------- #
# arguments
# --------------------------------------------------------------------------- #
def pop_choice(flag, choices):
    """Removes `flag VALUE` from sys.argv (before parse_args sees it) and returns VALUE, which
    must be one of `choices` (default: the first). Used by the shot variants of the scenes."""
    value = choices[0]
    if flag in sys.argv:
        i = sys.argv.index(flag)
        value = sys.argv[i + 1]
        del sys.argv[i:i + 2]
    if value not in choices:
        raise SystemExit("%s must be one of %s" % (flag, ", ".join(choices)))
    return value


def parse_size(text):
    """'1920x1080' -> (1920, 1080)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError("--size must be WxH, e.g. 1920x1080")
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError("--size must be positive")
    return (w, h)


def non_negative(text):
    v = int(text)
    if v < 0:
        raise argparse.ArgumentTypeError("must be >= 0")
    return v


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser()
    p.add_argument("--out", required=False)
    p.add_argument("--mode", choices=["main", "bounce1", "backfaces"], default="main")
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--frames", default="%d-%d" % FRAMES)
    p.add_argument("--size", type=parse_size, default=RES, metavar="WxH")
    p.add_argument("--bounces", type=non_negative, default=None, metavar="N")
    p.add_argument("--overscan", type=float, default=0.0, metavar="PERCENT")
    # The AO pass's distance (World > Ambient Occlusion > Distance), in metres: 1 matches
    # hbil's default radius (the samples' ao reference); a distance beyond the scene makes
    # the AO pass the fraction of each pixel's hemisphere that escapes the whole scene; 0
    # renders no AO pass.
    p.add_argument("--ao-distance", type=float, default=1.0, metavar="M")
    p.add_argument("--save-blend")
    p.add_argument("--no-render", action="store_true")
    return p.parse_args(argv)


# --------------------------------------------------------------------------- #
# scene building
# --------------------------------------------------------------------------- #
def clear_scene():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob, do_unlink=True)
    for coll in (bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras):
        for d in list(coll):
            coll.remove(d)
    scene = bpy.context.scene
    scene.unit_settings.system = 'METRIC'
    scene.unit_settings.scale_length = 1.0
    return scene


_materials = {}


def diffuse(name, color):
    """Pure Diffuse BSDF (roughness 0, i.e. Lambert)."""
    key = ("d", name)
    if key in _materials:
        return _materials[key]
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (color[0], color[1], color[2], 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    m.diffuse_color = (color[0], color[1], color[2], 1.0)
    _materials[key] = m
    return m


def emission(name, color, strength):
    key = ("e", name)
    if key in _materials:
        return _materials[key]
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (color[0], color[1], color[2], 1.0)
    em.inputs["Strength"].default_value = strength
    nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
    _materials[key] = m
    return m


def _finish(ob, name, mat, smooth=False):
    ob.name = name
    ob.data.name = name
    ob.data.materials.clear()
    ob.data.materials.append(mat)
    if smooth:
        for poly in ob.data.polygons:
            poly.use_smooth = True
    return ob


def box(name, mn, mx, mat, rot_z_deg=0.0):
    """Axis-aligned box from corner mn to corner mx (metres), optional yaw about its centre."""
    mn, mx = Vector(mn), Vector(mx)
    c = (mn + mx) / 2
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=c)
    ob = bpy.context.active_object
    ob.scale = mx - mn
    ob.rotation_euler[2] = math.radians(rot_z_deg)
    return _finish(ob, name, mat)


def cylinder(name, x, y, z0, z1, radius, mat, verts=24):
    bpy.ops.mesh.primitive_cylinder_add(vertices=verts, radius=radius, depth=z1 - z0,
                                        location=(x, y, (z0 + z1) / 2))
    ob = _finish(bpy.context.active_object, name, mat, smooth=True)
    # keep the caps flat: only the side faces are smooth
    for poly in ob.data.polygons:
        if abs(poly.normal.z) > 0.5:
            poly.use_smooth = False
    return ob


def sphere(name, loc, radius, mat):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=radius,
                                         location=loc)
    return _finish(bpy.context.active_object, name, mat, smooth=True)


def world(scene, color, strength=1.0):
    w = scene.world or bpy.data.worlds.new("World")
    scene.world = w
    w.use_nodes = True
    nt = w.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputWorld")
    bg = nt.nodes.new("ShaderNodeBackground")
    bg.inputs["Color"].default_value = (color[0], color[1], color[2], 1.0)
    bg.inputs["Strength"].default_value = strength
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    w.color = color
    return w


def sun(name, travel_dir, strength, angle_deg=1.0):
    """Sun whose light travels along ``travel_dir``."""
    ld = bpy.data.lights.new(name, 'SUN')
    ld.energy = strength
    ld.angle = math.radians(angle_deg)
    ob = bpy.data.objects.new(name, ld)
    bpy.context.scene.collection.objects.link(ob)
    d = Vector(travel_dir).normalized()
    ob.rotation_mode = 'QUATERNION'
    ob.rotation_quaternion = d.to_track_quat('-Z', 'Y')
    ob.location = -5 * d
    return ob


def area_light(name, loc, size, power, color=(1, 1, 1), travel_dir=(0, 0, -1)):
    ld = bpy.data.lights.new(name, 'AREA')
    ld.shape = 'SQUARE'
    ld.size = size
    ld.energy = power
    ld.color = color
    ob = bpy.data.objects.new(name, ld)
    bpy.context.scene.collection.objects.link(ob)
    ob.location = loc
    ob.rotation_mode = 'QUATERNION'
    ob.rotation_quaternion = Vector(travel_dir).normalized().to_track_quat('-Z', 'Y')
    return ob


def camera(name, lens_mm):
    cd = bpy.data.cameras.new(name)
    cd.lens = lens_mm
    cd.sensor_width = 36.0
    cd.sensor_height = 24.0
    cd.sensor_fit = 'AUTO'
    cd.clip_start = 0.05
    cd.clip_end = 200.0
    ob = bpy.data.objects.new(name, cd)
    bpy.context.scene.collection.objects.link(ob)
    bpy.context.scene.camera = ob
    return ob


def key(ob, frame, **props):
    for k, v in props.items():
        setattr(ob, k, v)
        ob.keyframe_insert(data_path=k, frame=frame)


def look(loc, target):
    """rotation_euler of a camera at loc looking at target (up = +Z)."""
    return (Vector(target) - Vector(loc)).to_track_quat('-Z', 'Y').to_euler()


def key_aimed(ob, frame, loc, target):
    """Keys ob at frame at location loc, looking at target (look())."""
    key(ob, frame, location=loc, rotation_euler=look(loc, target))


def smooth_fcurves(ob, interpolation='BEZIER'):
    if ob.animation_data and ob.animation_data.action:
        for fc in ob.animation_data.action.fcurves:
            for kp in fc.keyframe_points:
                kp.interpolation = interpolation


def hard_cut(ob, last_frame):
    """Linear keys everywhere, but the key at `last_frame` holds until the next key: the
    camera jumps there in one frame (a hard cut)."""
    smooth_fcurves(ob, 'LINEAR')
    for fc in ob.animation_data.action.fcurves:
        for kp in fc.keyframe_points:
            if int(round(kp.co[0])) == last_frame:
                kp.interpolation = 'CONSTANT'


# --------------------------------------------------------------------------- #
# render configuration
# --------------------------------------------------------------------------- #
def configure(scene, mode, samples, seed, ao_distance=1.0, size=RES, bounces=None):
    """bounces: None = the mode's own (main 8, otherwise 1); N overrides max_bounces and
    diffuse_bounces (0 = direct light only)."""
    scene.frame_start, scene.frame_end = FRAMES
    r = scene.render
    r.engine = 'CYCLES'
    r.resolution_x, r.resolution_y = size
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    r.use_motion_blur = False
    r.use_persistent_data = False
    r.threads_mode = 'AUTO'
    r.film_transparent = False
    r.use_compositing = False
    r.use_sequencer = False
    r.filter_size = 1.5  # Cycles default (Blackman-Harris, 1.5 px)
    r.use_file_extension = True
    r.use_overwrite = True
    r.use_placeholder = False

    im = r.image_settings
    im.file_format = 'OPEN_EXR_MULTILAYER'
    im.color_depth = '32'
    im.exr_codec = 'ZIP'
    im.use_preview = False

    c = scene.cycles
    c.device = 'CPU'
    c.feature_set = 'SUPPORTED'
    c.samples = samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.use_preview_denoising = False
    c.seed = seed
    c.use_animated_seed = False
    c.pixel_filter_type = 'BLACKMAN_HARRIS'
    c.filter_width = 1.5
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.caustics_reflective = False
    c.caustics_refractive = False
    c.blur_glossy = 0.0
    c.glossy_bounces = 0
    c.transmission_bounces = 0
    c.volume_bounces = 0
    c.transparent_max_bounces = 8
    c.use_fast_gi = False
    if hasattr(c, "use_light_tree"):  # Blender >= 3.5
        c.use_light_tree = False
    if mode == "main":
        c.max_bounces = 8
        c.diffuse_bounces = 8
    else:
        c.max_bounces = 1
        c.diffuse_bounces = 1
    if bounces is not None:
        c.max_bounces = bounces
        c.diffuse_bounces = bounces

    # World > Ambient Occlusion distance drives the AO pass
    scene.world.light_settings.distance = ao_distance
    scene.world.light_settings.use_ambient_occlusion = False

    for vl in scene.view_layers:
        vl.use = False
    vl = scene.view_layers[0]
    vl.name = "ViewLayer"
    vl.use = True
    main = mode == "main"
    vl.use_pass_combined = main
    vl.use_pass_z = True
    vl.use_pass_mist = False
    vl.use_pass_normal = main
    vl.use_pass_position = main
    vl.use_pass_vector = main
    vl.use_pass_diffuse_color = True
    vl.use_pass_diffuse_direct = True
    vl.use_pass_diffuse_indirect = True
    vl.use_pass_glossy_color = False
    vl.use_pass_glossy_direct = False
    vl.use_pass_glossy_indirect = False
    vl.use_pass_transmission_color = False
    vl.use_pass_transmission_direct = False
    vl.use_pass_transmission_indirect = False
    vl.use_pass_emit = main
    vl.use_pass_environment = main
    vl.use_pass_ambient_occlusion = main and ao_distance > 0
    vl.use_pass_object_index = False
    vl.use_pass_material_index = False
    vl.cycles.denoising_store_passes = False
    vl.cycles.use_pass_shadow_catcher = False
    vl.use_pass_cryptomatte_object = False
    if mode == "backfaces":
        vl.use = False
        import backfaces  # noqa: E402  (same folder, on sys.path)
        backfaces.add_backface_layer(scene, samples=1)


# --------------------------------------------------------------------------- #
# render loop
# --------------------------------------------------------------------------- #
class Overscan:
    """A guard band of `percent` % of the frame's size on each side: the render grows by
    2 gx x 2 gy pixels and the sensor with it, so that the focal length in pixels and the
    principal point (the centre) stay where the original framing has them."""

    def __init__(self, scene, percent):
        r = scene.render
        self.w, self.h = r.resolution_x, r.resolution_y
        self.gx = int(round(self.w * percent / 100.0))
        self.gy = int(round(self.h * percent / 100.0))
        self.cam = scene.camera.data
        self.sensor = (self.cam.sensor_width, self.cam.sensor_height)
        if self.cam.sensor_fit != 'AUTO' or self.w < self.h:
            raise SystemExit("--overscan needs a landscape frame with sensor_fit AUTO")
        if abs(self.cam.shift_x) + abs(self.cam.shift_y) > 0:
            raise SystemExit("--overscan needs a camera without shift")

    def grow(self, scene):
        scale = (self.w + 2 * self.gx) / self.w
        scene.render.resolution_x = self.w + 2 * self.gx
        scene.render.resolution_y = self.h + 2 * self.gy
        self.cam.sensor_width = self.sensor[0] * scale
        self.cam.sensor_height = self.sensor[1] * scale
        bpy.context.view_layer.update()

    def original(self, scene):
        scene.render.resolution_x, scene.render.resolution_y = self.w, self.h
        self.cam.sensor_width, self.cam.sensor_height = self.sensor
        bpy.context.view_layer.update()


def render_frames(scene, out_dir, frames, overscan=None):
    out_dir = os.path.abspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    pattern = os.path.join(out_dir, "frame_####")
    times = []
    for f in frames:
        scene.render.filepath = pattern
        exr = scene.render.frame_path(frame=f)  # .../frame_0003.exr
        # write_still does not expand '#': give it the expanded name
        scene.render.filepath = exr
        scene.frame_set(f)
        t0, c0 = time.time(), time.process_time()
        bpy.ops.render.render(write_still=True)
        dt = time.time() - t0
        cpu = time.process_time() - c0  # CPU seconds of all render threads
        times.append(dt)
        scene.render.filepath = pattern
        if overscan:
            # The sidecar describes the display window: the original framing.
            overscan.original(scene)
        side = export_camera.write_sidecar(scene, exr, f, bpy.context.evaluated_depsgraph_get())
        if overscan:
            overscan.grow(scene)
            import repack_exr  # numpy and OpenImageIO, which Blender's Python has
            repack_exr.set_windows(exr, -overscan.gx, -overscan.gy, overscan.w, overscan.h)
        print("HBIL_FRAME scene=%s frame=%d seconds=%.2f cpu_seconds=%.2f samples=%d "
              "file=%s sidecar=%s"
              % (scene.name, f, dt, cpu, scene.cycles.samples, exr, os.path.basename(side)),
              flush=True)
    if times:
        print("HBIL_TIMING frames=%d mean_seconds=%.2f total_seconds=%.1f"
              % (len(times), sum(times) / len(times), sum(times)), flush=True)
    return times


def run(name, build, film_transparent=False):
    """Entry point used by the scene scripts: build(scene) creates the scene.
    film_transparent: the world is not rendered where nothing is hit (Combined alpha 0 there,
    premultiplied colour elsewhere), as for a render to be composited over a plate."""
    a = parse_args()
    scene = clear_scene()
    scene.name = name
    build(scene)
    configure(scene, a.mode, a.samples, a.seed, ao_distance=a.ao_distance, size=a.size,
              bounces=a.bounces)
    scene.render.film_transparent = film_transparent
    if a.save_blend:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save_blend), compress=True)
    if a.no_render:
        return
    if not a.out:
        raise SystemExit("--out DIR is required to render")
    overscan = None
    if a.overscan > 0:
        overscan = Overscan(scene, a.overscan)
        overscan.grow(scene)
    render_frames(scene, a.out, export_camera.parse_frames(a.frames), overscan)
