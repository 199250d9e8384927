"""Add a "BackFaces" view layer whose Depth pass is the depth of the first back face.

hbil's visibility bitmask (method "bitmask") treats every depth sample as an occluder of some
thickness behind it. With this layer it uses each pixel's real thickness, the length of its
view ray inside the object (man hbil: passes.backdepth), instead of one constant.

How it works: the layer's material override is a mix, by Geometry > Backfacing, of a fully
transparent shader on front faces and an opaque one on back faces. Cycles writes the Depth pass
at the first surface whose alpha reaches the view layer's pass alpha threshold (0.5), so the
camera ray passes through the front face and records the back face behind it. Where the ray
leaves the scene without meeting a back face the depth is background (1e10), and hbil falls
back to the constant thickness there. One sample per pixel is enough: the Depth pass is taken
from the first sample, and with the same seed that is the same sub-pixel ray as the main layer's.
Closed meshes (boxes, cylinders, spheres) give exact thicknesses; a single-sided plane has none.

Use on a scene of your own (Blender 3.4), then render as usual; the multilayer EXR then holds
BackFaces.Depth.Z next to ViewLayer.*:

    blender -b shot.blend --python samples/blender/backfaces.py -a

or from another script: ``import backfaces; backfaces.add_backface_layer(scene)``.
"""

import bpy

LAYER = "BackFaces"


def backface_material():
    """Transparent front faces, opaque black back faces."""
    m = bpy.data.materials.get("hbil_backfaces")
    if m is not None:
        return m
    m = bpy.data.materials.new("hbil_backfaces")
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    mix = nt.nodes.new("ShaderNodeMixShader")
    front = nt.nodes.new("ShaderNodeBsdfTransparent")
    back = nt.nodes.new("ShaderNodeEmission")
    back.inputs["Color"].default_value = (0, 0, 0, 1)
    nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
    nt.links.new(front.outputs["BSDF"], mix.inputs[1])  # Fac 0: front face
    nt.links.new(back.outputs["Emission"], mix.inputs[2])  # Fac 1: back face
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return m


def add_backface_layer(scene, samples=1):
    """Adds (or refreshes) the BackFaces view layer of `scene`; returns it."""
    vl = scene.view_layers.get(LAYER) or scene.view_layers.new(LAYER)
    vl.use = True
    vl.material_override = backface_material()
    vl.samples = samples  # per-layer sample count (0 = the scene's)
    vl.pass_alpha_threshold = 0.5
    vl.use_pass_combined = False
    vl.use_pass_z = True
    for attr in ("use_pass_mist", "use_pass_normal", "use_pass_position", "use_pass_vector",
                 "use_pass_diffuse_color", "use_pass_diffuse_direct",
                 "use_pass_diffuse_indirect", "use_pass_glossy_color", "use_pass_glossy_direct",
                 "use_pass_glossy_indirect", "use_pass_transmission_color",
                 "use_pass_transmission_direct", "use_pass_transmission_indirect",
                 "use_pass_emit", "use_pass_environment", "use_pass_ambient_occlusion",
                 "use_pass_object_index", "use_pass_material_index"):
        if hasattr(vl, attr):
            setattr(vl, attr, False)
    return vl


if __name__ == "__main__":
    for s in bpy.data.scenes:
        add_backface_layer(s)
        print("hbil: added view layer %s to scene %s" % (LAYER, s.name), flush=True)
