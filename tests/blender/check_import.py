# Run inside Blender (blender -b --python-exit-code 1 -P check_import.py -- EXPORT_DIR ADDON):
# Blender's own importers read body.glb (armature with the export's joints; a posed bone moves
# vertices) and fur.obj (one edge per strand segment), and the add-on builds hair curves attached to
# the body with the .hair file's curve and point counts, its colours as a `strand_color` attribute and a
# hair material that reads it; a small Cycles render of the curves shows the groom's colour. Any
# failed check raises: exit code 1.
import importlib.util
import json
import os
import sys

import bpy
import numpy as np

folder, addon_path = sys.argv[sys.argv.index("--") + 1:][:2]
record = json.load(open(os.path.join(folder, "export.json")))
spec = importlib.util.spec_from_file_location("nf_gpu_import", addon_path)
addon = importlib.util.module_from_spec(spec)
spec.loader.exec_module(addon)
counts, points, _, colors = addon.read_hair(os.path.join(folder, "fur.hair"))
results = {}


def turn_head(armature, radians=0.6):
    bone = armature.pose.bones["head"]
    bone.rotation_mode = "XYZ"
    bone.rotation_euler = (radians, 0.0, 0.0)
    bpy.context.view_layer.update()


def check(name, ok, detail):
    results[name] = {"ok": bool(ok), "detail": detail}
    print(f"nf_gpu blender test: {'PASS' if ok else 'FAIL'} {name}: {detail}")


# 1. body.glb through Blender's glTF importer.
bpy.ops.wm.read_factory_settings(use_empty=True)
# Smooth shading: Debian's Blender 3.4 with numpy 1.24 fails in the default "NORMALS" mode (np.bool).
bpy.ops.import_scene.gltf(filepath=os.path.join(folder, "body.glb"), import_shading="SMOOTH")
armature = next(o for o in bpy.data.objects if o.type == "ARMATURE")
body = next(o for o in bpy.data.objects if o.type == "MESH")
check("armature bones", len(armature.data.bones) == record["joints"], f"{len(armature.data.bones)} bones, export.json says {record['joints']}")


def evaluated_coordinates():
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = body.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    xyz = np.empty(3 * len(mesh.vertices), np.float64)
    mesh.vertices.foreach_get("co", xyz)
    evaluated.to_mesh_clear()
    return xyz.reshape(-1, 3)


rest = evaluated_coordinates()
turn_head(armature)
posed = evaluated_coordinates()
moved = int(np.count_nonzero(np.linalg.norm(posed - rest, axis=1) > 1e-4))
check("posed bone moves vertices", 0 < moved < len(rest) // 2, f"rotating 'head' moved {moved} of {len(rest)} vertices")

# 2. fur.obj and fur.ply through Blender's importers: polylines and vertex chains become edges.
# Blender 3.4's new OBJ importer (wm.obj_import) keeps only the first segment of an `l` polyline
# (measured here and reported, not asserted); its legacy importer reads them whole.
want_edges = int(counts.sum() - len(counts))
for name, importer in (("fur.obj (legacy OBJ importer)", lambda p: bpy.ops.import_scene.obj(filepath=p)),
                       ("fur.ply (PLY importer)", lambda p: bpy.ops.import_mesh.ply(filepath=p))):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    importer(os.path.join(folder, name.split()[0]))
    mesh = next(o for o in bpy.data.objects if o.type == "MESH")
    check(name + " edges", len(mesh.data.edges) == want_edges and len(mesh.data.vertices) == int(counts.sum()),
          f"{len(mesh.data.edges)} edges and {len(mesh.data.vertices)} vertices; the groom has {want_edges} segments, {int(counts.sum())} points")
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath=os.path.join(folder, "fur.obj"))
mesh = next(o for o in bpy.data.objects if o.type == "MESH")
print(f"nf_gpu blender test: INFO the new OBJ importer of Blender {bpy.app.version_string} made {len(mesh.data.edges)} edges of {want_edges}")

# 3. The add-on: Blender hair curves on the body's surface.
bpy.ops.wm.read_factory_settings(use_empty=True)
report = addon.import_groom(folder)
check("hair curves", report["curves"] == len(counts), f"{report['curves']} curves, fur.hair has {len(counts)} strands")
check("hair points", report["points"] == int(counts.sum()), f"{report['points']} points, fur.hair has {int(counts.sum())}")
check("attached to the body", report["surface"] == report["body"] and report["attached_curves"] == report["curves"],
      f"surface {report['surface']}, UV map {report['surface_uv_map']}, {report['attached_curves']} of {report['curves']} curves have a surface coordinate")
check("rig imported", report["bones"] == record["joints"], f"{report['bones']} bones")
# The hair follows the skin: posing the head moves the curves rooted there, not the others.
hair = bpy.data.objects["nf_gpu_fur"]
rig = next(o for o in bpy.data.objects if o.type == "ARMATURE")


def hair_points():
    evaluated = hair.evaluated_get(bpy.context.evaluated_depsgraph_get())
    xyz = np.empty(3 * len(evaluated.data.points), np.float64)
    evaluated.data.points.foreach_get("position", xyz)
    return xyz.reshape(-1, 3)


before = hair_points()
turn_head(rig)
moved = int(np.count_nonzero(np.linalg.norm(hair_points() - before, axis=1) > 1e-5))
check("hair follows the posed skin", 0 < moved < len(before) // 2, f"rotating 'head' moved {moved} of {len(before)} hair points")

# The colours: the file's, on every point, and a Principled Hair BSDF fed by them.
attribute = hair.data.attributes.get("strand_color")
check("colour attribute", attribute is not None and colors is not None and len(attribute.data) == len(colors),
      f"{'no' if attribute is None else len(attribute.data)} colours on the curves, fur.hair has {'none' if colors is None else len(colors)}")
if attribute is not None and colors is not None:
    rgba = np.empty(4 * len(attribute.data), np.float32)
    attribute.data.foreach_get("color", rgba)
    off = float(np.abs(rgba.reshape(-1, 4)[:, :3] - colors).max()) if len(colors) else 0.0
    check("colour values", off < 1e-6, f"largest difference from fur.hair's colours {off:.2e}")
material = hair.data.materials[0] if len(hair.data.materials) else None
bsdf = next((n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfHairPrincipled"), None) if material else None
fed = bsdf is not None and bsdf.inputs["Color"].is_linked and bsdf.inputs["Color"].links[0].from_node.bl_idname == "ShaderNodeAttribute" \
    and bsdf.inputs["Color"].links[0].from_node.attribute_name == "strand_color"
check("hair material", fed, f"material {material.name if material else None}: Principled Hair BSDF {'fed by the strand_color attribute' if fed else 'missing or not fed'}")


def glb_vertex_colors(path):
    """body.glb's COLOR_0 (linear RGB per vertex), read from the file itself, or None."""
    import struct
    data = open(path, "rb").read()
    length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + length])
    binary = data[20 + length + 8:]
    primitive = gltf["meshes"][0]["primitives"][0]
    if "COLOR_0" not in primitive["attributes"]:
        return None
    accessor = gltf["accessors"][primitive["attributes"]["COLOR_0"]]
    view = gltf["bufferViews"][accessor["bufferView"]]
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    return np.frombuffer(binary, np.float32, 3 * accessor["count"], start).reshape(-1, 3)


# The body's colours: body.glb's COLOR_0 as the body's colour attribute (per vertex or per corner,
# as the importer chooses), and a material fed by it.
want = glb_vertex_colors(os.path.join(folder, "body.glb"))
body = bpy.data.objects[report["body"]]
name = report["body_colors"]
if want is None:
    check("body colours", name is None, "body.glb has no COLOR_0; the body has " + ("none" if name is None else f"an attribute {name}"))
else:
    attribute = body.data.color_attributes.get(name) if name else None
    off = None
    if attribute is not None:
        rgba = np.empty(4 * len(attribute.data), np.float32)
        attribute.data.foreach_get("color", rgba)
        got = rgba.reshape(-1, 4)[:, :3]
        if attribute.domain == "CORNER":
            vertex_of = np.empty(len(body.data.loops), np.int64)
            body.data.loops.foreach_get("vertex_index", vertex_of)
            expected = want[vertex_of]
        else:
            expected = want[:len(got)]
        # The importer keeps glTF's vertex order only up to its own de-duplication: compare where
        # the counts agree, else the means.
        off = float(np.abs(got - expected).max()) if len(got) == len(expected) else float(np.abs(got.mean(0) - want.mean(0)).max())
    # Byte colours hold 8-bit sRGB: about 0.01 in linear light near white.
    check("body colours", attribute is not None and off < 0.02,
          f"attribute {name} ({'absent' if attribute is None else attribute.domain + ', ' + attribute.data_type}); "
          f"largest difference from body.glb's COLOR_0 {'n/a' if off is None else f'{off:.4f}'}")
    surface = next((n for n in body.data.materials[0].node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled"), None) \
        if len(body.data.materials) else None
    fed = surface is not None and surface.inputs["Base Color"].is_linked and \
        surface.inputs["Base Color"].links[0].from_node.bl_idname == "ShaderNodeAttribute" and \
        surface.inputs["Base Color"].links[0].from_node.attribute_name == name
    check("body material", fed, f"material {report['body_material']}: Principled BSDF {'fed by ' + str(name) if fed else 'missing or not fed'}")


def render_curves():
    """The hair alone (body hidden) in a small Cycles render under a white sky: its mean colour's
    chromaticity (r, g, b over their sum), weighted by coverage."""
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 16
    scene.cycles.use_denoising = False  # Debian's Cycles is built without OpenImageDenoise
    scene.render.resolution_x = scene.render.resolution_y = 96
    scene.render.film_transparent = True
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.world = bpy.data.worlds.new("white") if scene.world is None else scene.world
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (1, 1, 1, 1)
    for o in bpy.data.objects:
        if o.type == "MESH":
            o.hide_render = True
    # Strands a hair wide are a hundredth of a pixel here: widened so the render has pixels to read.
    radius = hair.data.attributes.get("radius")
    if radius is not None:
        r = np.empty(len(radius.data), np.float32)
        radius.data.foreach_get("value", r)
        radius.data.foreach_set("value", r * 60)
    xyz = hair_points()
    centre, size = xyz.mean(axis=0), float(np.ptp(xyz, axis=0).max())
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    from mathutils import Vector
    camera.location = Vector(centre) + Vector((0, -1.6 * size, 0.4 * size))
    camera.rotation_euler = (Vector(centre) - camera.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    out = os.path.join(os.path.dirname(folder.rstrip("/")), "blender_render.exr")
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(out)
    px = np.array(image.pixels[:], np.float64).reshape(-1, 4)
    covered = px[:, 3] > 0.02
    rgb = (px[covered, :3] * px[covered, 3:4]).sum(axis=0)
    return rgb / max(rgb.sum(), 1e-9), int(covered.sum())


if colors is not None and len(colors):
    # The hair's white primary reflection (Principled Hair's R lobe) desaturates the render, so the
    # check is on the hue: the rendered colour lies off grey in the groom's direction (within 20
    # degrees in the chromaticity plane) and keeps a share of its saturation.
    rendered, pixels = render_curves()
    wanted = colors.mean(axis=0) / max(float(colors.mean(axis=0).sum()), 1e-9)
    a, b = rendered - 1 / 3, wanted - 1 / 3
    cosine = float(a @ b / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-12))
    saturation = float(np.linalg.norm(a) / max(np.linalg.norm(b), 1e-12))
    check("render shows the colours", pixels > 20 and cosine > np.cos(np.radians(20)) and saturation > 0.15,
          f"{pixels} hair pixels; chromaticity {np.round(rendered, 3).tolist()} against the groom's {np.round(wanted, 3).tolist()}: "
          f"hue {np.degrees(np.arccos(min(1.0, cosine))):.1f} degrees off, {100 * saturation:.0f} % of its saturation")

# 4. The add-on installs and enables from Blender's preferences (what a user does once).
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.preferences.addon_install(filepath=addon_path, overwrite=True)
bpy.ops.preferences.addon_enable(module="nf_gpu_import")
menu = hasattr(bpy.ops.import_scene, "nf_gpu_groom") and "nf_gpu_import" in bpy.context.preferences.addons
check("add-on installs", menu, "File > Import > nf_gpu groom is " + ("registered" if menu else "missing"))
# Leave the user's Blender as it was (the preferences' remove operator needs a window).
import addon_utils  # noqa: E402  (Blender's module)
addon_utils.disable("nf_gpu_import")
installed = os.path.join(bpy.utils.user_resource("SCRIPTS", path="addons"), "nf_gpu_import.py")
if os.path.exists(installed):
    os.remove(installed)

print("nf_gpu blender test:", json.dumps({"blender": bpy.app.version_string, "results": results}))
if not all(r["ok"] for r in results.values()):
    raise SystemExit(1)
