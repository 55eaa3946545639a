# nf_gpu result -> Blender: the rigged body (body.glb) and the groom (fur.hair) as Blender's native
# hair curves (the Curves object of Blender 3.3+) attached to the body's surface, so Blender's hair
# tools can comb, cut and grow it; the strands' colours from the photos become the curves'
# `strand_color` attribute, shown by a Principled Hair BSDF (render with Cycles; Cycles 3.4 reads no
# attribute named `color` on hair curves).
#
# As an add-on: Edit > Preferences > Add-ons > Install..., pick this file, enable "nf_gpu groom
# import"; then File > Import > nf_gpu groom (pick the export folder's export.json).
# Headless:   blender -b -P tools/blender/nf_gpu_import.py -- EXPORT_DIR [--save OUT.blend]
#             [--max-strands N] [--points-per-strand P] [--report REPORT.json]
#             [--render OUT.png [--size W H] [--samples S]]   (a Cycles still: front three-quarter view)
#
# Debian's Blender 3.4 is built without USD and Alembic, which is why this add-on exists: it reads
# the formats nf_gpu writes (glTF and Cem Yuksel's .hair) with Blender's own glTF importer and a
# small .hair reader, and builds the hair curves through Blender's operators (3.4 has no Python API
# that adds curves to a Curves object: an edge mesh becomes a legacy curve, then hair curves).
bl_info = {
    "name": "nf_gpu groom import",
    "author": "nf_gpu",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > nf_gpu groom",
    "description": "Imports an nf_gpu export folder: rigged body and hair curves attached to it",
    "category": "Import-Export",
}

import json
import os
import struct
import sys

import bpy
import numpy as np

HAIR_SEGMENTS, HAIR_POINTS, HAIR_THICKNESS, HAIR_TRANSPARENCY, HAIR_COLORS = 1, 2, 4, 8, 16

# Debian 12 pairs Blender 3.4 with numpy 1.24, which removed `np.bool`; the glTF importer of 3.4
# still uses it when it guesses flat faces from normals (import_shading="NORMALS", its default),
# and fails. The add-on imports with smooth shading, which avoids that code; restoring the alias
# (numpy's own bool type, what the name meant) also mends File > Import > glTF for the session.
if "bool" not in np.__dict__:
    np.bool = np.bool_


def read_hair(path):
    """Cem Yuksel's .hair: (points per strand array, xyz float32 array (N, 3), thickness or None,
    linear RGB colours (N, 3) or None)."""
    with open(path, "rb") as f:
        header = f.read(128)
        if len(header) < 128 or header[:4] != b"HAIR":
            raise ValueError(f"{path}: not a .hair file")
        hair_count, point_count, arrays, default_segments = struct.unpack_from("<4I", header, 4)
        if not arrays & HAIR_POINTS:
            raise ValueError(f"{path}: the file has no points array")
        if arrays & HAIR_SEGMENTS:
            counts = np.frombuffer(f.read(2 * hair_count), dtype="<u2").astype(np.int64) + 1
        else:
            counts = np.full(hair_count, default_segments + 1, dtype=np.int64)
        if int(counts.sum()) != point_count:
            raise ValueError(f"{path}: strands hold {int(counts.sum())} points, the header says {point_count}")
        points = np.frombuffer(f.read(12 * point_count), dtype="<f4").reshape(-1, 3)
        if len(points) != point_count:
            raise ValueError(f"{path}: truncated points array")
        thickness = colors = None
        if arrays & HAIR_THICKNESS:
            thickness = np.frombuffer(f.read(4 * point_count), dtype="<f4")
        if arrays & HAIR_TRANSPARENCY:
            f.read(4 * point_count)
        if arrays & HAIR_COLORS:
            colors = np.frombuffer(f.read(12 * point_count), dtype="<f4").reshape(-1, 3)
            if len(colors) != point_count:
                raise ValueError(f"{path}: truncated colour array")
    return counts, points, thickness, colors


def select_strands(counts, per_point, max_strands, points_per_strand):
    """An even subset of the strands, each resampled to `points_per_strand` points (0: as they are):
    (the strands kept, their point counts, and each array of `per_point` (one row per point, or
    None) for the points kept)."""
    n = len(counts)
    keep = np.arange(n) if not max_strands or max_strands >= n else np.linspace(0, n - 1, max_strands).astype(np.int64)
    if n and np.all(counts == counts[0]):  # nf_gpu's grooms: every strand has the same count, so no loop
        c = int(counts[0])
        pick = np.arange(c) if not points_per_strand or c <= points_per_strand else np.linspace(0, c - 1, points_per_strand).round().astype(np.int64)
        picked = [None if a is None else a.reshape((n, c) + a.shape[1:])[keep][:, pick].reshape((-1,) + a.shape[1:]) for a in per_point]
        return keep, np.full(len(keep), len(pick), dtype=np.int64), picked
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    out_counts, out = [], [[] for _ in per_point]
    for s in keep:
        c = int(counts[s])
        pick = np.arange(c)
        if points_per_strand and c > points_per_strand:
            pick = np.linspace(0, c - 1, points_per_strand).round().astype(np.int64)
        out_counts.append(len(pick))
        for a, o in zip(per_point, out):
            if a is not None:
                o.append(a[starts[s]:starts[s] + c][pick])
    picked = [None if a is None else (np.concatenate(o) if o else a[:0]) for a, o in zip(per_point, out)]
    return keep, np.array(out_counts, dtype=np.int64), picked


def import_body(folder):
    before = set(bpy.data.objects)
    bpy.ops.import_scene.gltf(filepath=os.path.join(folder, "body.glb"), import_shading="SMOOTH")
    new = [o for o in bpy.data.objects if o not in before]
    body = next((o for o in new if o.type == "MESH"), None)
    armature = next((o for o in new if o.type == "ARMATURE"), None)
    if body is None:
        raise RuntimeError(f"{folder}/body.glb: no mesh was imported")
    colors = body_color_attribute(body)
    if colors is not None:
        body.data.materials.clear()
        body.data.materials.append(body_material("nf_gpu body", colors))
    return body, armature


def body_color_attribute(body):
    """The name of the body's colour attribute (glTF COLOR_0: the body's colours from the photos),
    or None. The importer's name for it differs between Blender versions ("Col", "Color")."""
    attributes = getattr(body.data, "color_attributes", None)
    if attributes is not None and len(attributes):
        return attributes[0].name
    return None


def body_material(name, attribute_name):
    """A matte material for the body fed by its colour attribute: where the coat parts or is thin
    the body shows the fur's colour there, and bald skin (nose, pads) its own."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    attribute = nodes.new("ShaderNodeAttribute")
    attribute.attribute_name = attribute_name
    surface = nodes.new("ShaderNodeBsdfPrincipled")
    surface.inputs["Roughness"].default_value = 0.8
    specular = surface.inputs.get("Specular") or surface.inputs.get("Specular IOR Level")  # renamed in Blender 4
    if specular is not None:
        specular.default_value = 0.2
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(attribute.outputs["Color"], surface.inputs["Base Color"])
    links.new(surface.outputs[0], output.inputs["Surface"])
    attribute.location, surface.location, output.location = (-400, 0), (-150, 0), (150, 0)
    return material


def hair_material(name):
    """A hair material that shades each strand with its own colour: Principled Hair BSDF (Cycles)
    with its colour from the curves' `strand_color` attribute (linear RGB from the photos)."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    attribute = nodes.new("ShaderNodeAttribute")
    attribute.attribute_name = "strand_color"
    hair = nodes.new("ShaderNodeBsdfHairPrincipled")
    hair.parametrization = "COLOR"
    hair.inputs["Roughness"].default_value = 0.4
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(attribute.outputs["Color"], hair.inputs["Color"])
    links.new(hair.outputs[0], output.inputs["Surface"])
    attribute.location, hair.location, output.location = (-400, 0), (-150, 0), (150, 0)
    return material


def make_hair_curves(name, counts, points, radii, regions, body, colors=None):
    """Blender hair curves (Curves object) with the given strands, attached to `body`'s surface;
    with `colors` (linear RGB per point) a `strand_color` attribute and a hair material that shows it."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(points))
    mesh.vertices.foreach_set("co", points.astype(np.float32).ravel())
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    first = np.concatenate([np.arange(s, s + c - 1) for s, c in zip(starts, counts)]) if len(counts) else np.zeros(0, np.int64)
    edges = np.stack([first, first + 1], axis=1).astype(np.int32)
    mesh.edges.add(len(edges))
    mesh.edges.foreach_set("vertices", edges.ravel())
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    for o in bpy.context.selected_objects:
        o.select_set(False)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    bpy.ops.object.convert(target="CURVE")   # edge chains -> poly splines, in strand order
    bpy.ops.object.convert(target="CURVES")  # -> hair curves
    hair = bpy.context.view_layer.objects.active
    if hair.type != "CURVES" or len(hair.data.curves) != len(counts):
        raise RuntimeError(f"hair curves: expected {len(counts)} curves, Blender made {len(hair.data.curves) if hair.type == 'CURVES' else hair.type}")
    hair.name = name
    if radii is not None:
        attribute = hair.data.attributes.get("radius") or hair.data.attributes.new("radius", "FLOAT", "POINT")
        attribute.data.foreach_set("value", radii.astype(np.float32))
    if regions is not None:
        attribute = hair.data.attributes.new("region", "INT", "CURVE")
        attribute.data.foreach_set("value", regions.astype(np.int32))
    if colors is not None:
        attribute = hair.data.attributes.new("strand_color", "FLOAT_COLOR", "POINT")
        rgba = np.concatenate([colors.astype(np.float32), np.ones((len(colors), 1), np.float32)], axis=1)
        attribute.data.foreach_set("color", rgba.ravel())
        hair.data.materials.append(hair_material(name + " colours"))
    # Attach to the body: a UV map on the surface, then Blender's own snapping records each curve's
    # surface coordinate (the roots lie on the skin, so the nearest point is the root's place).
    if not body.data.uv_layers:
        for o in bpy.context.selected_objects:
            o.select_set(False)
        bpy.context.view_layer.objects.active = body
        body.select_set(True)
        bpy.ops.object.mode_set(mode="EDIT")
        bpy.ops.mesh.select_all(action="SELECT")
        bpy.ops.uv.smart_project(island_margin=0.002)
        bpy.ops.object.mode_set(mode="OBJECT")
    hair.data.surface = body
    hair.data.surface_uv_map = body.data.uv_layers[0].name
    for o in bpy.context.selected_objects:
        o.select_set(False)
    bpy.context.view_layer.objects.active = hair
    hair.select_set(True)
    bpy.ops.curves.snap_curves_to_surface(attach_mode="NEAREST")
    hair.parent = body
    hair.matrix_parent_inverse = body.matrix_world.inverted()
    follow_skin(hair, body)
    return hair


def follow_skin(hair, body):
    """The curves follow the body's deformation (the armature): Blender's Deform Curves on Surface
    node, which needs the surface's undeformed positions as a `rest_position` attribute."""
    coordinates = np.empty(3 * len(body.data.vertices), np.float32)
    body.data.vertices.foreach_get("co", coordinates)
    rest = body.data.attributes.get("rest_position") or body.data.attributes.new("rest_position", "FLOAT_VECTOR", "POINT")
    rest.data.foreach_set("vector", coordinates)
    tree = bpy.data.node_groups.new("nf_gpu follow the skin", "GeometryNodeTree")
    tree.inputs.new("NodeSocketGeometry", "Geometry")
    tree.outputs.new("NodeSocketGeometry", "Geometry")
    group_in, group_out = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    deform = tree.nodes.new("GeometryNodeDeformCurvesOnSurface")
    tree.links.new(group_in.outputs[0], deform.inputs[0])
    tree.links.new(deform.outputs[0], group_out.inputs[0])
    modifier = hair.modifiers.new("nf_gpu follow the skin", "NODES")
    modifier.node_group = tree


def import_groom(folder, max_strands=0, points_per_strand=0):
    """Imports an nf_gpu export folder; returns a report (what the tests check)."""
    folder = os.path.abspath(folder)
    record = json.load(open(os.path.join(folder, "export.json")))
    body, armature = import_body(folder)
    counts, points, thickness, colors = read_hair(os.path.join(folder, "fur.hair"))
    regions = None
    roots_file = os.path.join(folder, "roots.npz")
    if os.path.exists(roots_file):
        regions = np.load(roots_file)["region"]
    keep, sel_counts, (sel_points, sel_thick, sel_colors) = select_strands(counts, [points, thickness, colors], max_strands, points_per_strand)
    # glTF's +y up becomes Blender's +z up: the same conversion Blender's glTF importer applies.
    converted = np.stack([sel_points[:, 0], -sel_points[:, 2], sel_points[:, 1]], axis=1) if len(sel_points) else sel_points
    hair = make_hair_curves("nf_gpu_fur", sel_counts, converted, None if sel_thick is None else 0.5 * sel_thick,
                            None if regions is None else regions[keep], body, sel_colors)
    surface_uv = hair.data.attributes.get("surface_uv_coordinate")
    uv = np.zeros(2 * len(hair.data.curves), np.float32)
    if surface_uv is not None:
        surface_uv.data.foreach_get("vector", uv)
    return {
        "blender": bpy.app.version_string,
        "strands_in_file": int(len(counts)),
        "points_in_file": int(counts.sum()),
        "curves": len(hair.data.curves),
        "points": len(hair.data.points),
        "expected_curves": int(len(sel_counts)),
        "expected_points": int(sel_counts.sum()),
        "surface": hair.data.surface.name if hair.data.surface else None,
        "surface_uv_map": hair.data.surface_uv_map,
        "attached_curves": int(np.count_nonzero(np.abs(uv.reshape(-1, 2)).sum(axis=1) > 0)),
        "body": body.name,
        "body_vertices": len(body.data.vertices),
        "body_colors": body_color_attribute(body),
        "body_material": body.data.materials[0].name if len(body.data.materials) else None,
        "armature": armature.name if armature else None,
        "bones": len(armature.data.bones) if armature else 0,
        "strands_exported": record.get("strands"),
        "colors": sel_colors is not None,
        "material": hair.data.materials[0].name if len(hair.data.materials) else None,
    }


class ImportNfGpuGroom(bpy.types.Operator):
    """Import an nf_gpu export folder (body.glb and fur.hair) as a rigged body with hair curves"""
    bl_idname = "import_scene.nf_gpu_groom"
    bl_label = "Import nf_gpu groom"
    bl_options = {"REGISTER", "UNDO"}
    filepath: bpy.props.StringProperty(subtype="FILE_PATH")
    filter_glob: bpy.props.StringProperty(default="export.json", options={"HIDDEN"})
    max_strands: bpy.props.IntProperty(name="Max strands", default=100000, min=0, description="0: all")
    points_per_strand: bpy.props.IntProperty(name="Points per strand", default=32, min=0, description="0: as in the file")

    def execute(self, context):
        report = import_groom(os.path.dirname(self.filepath), self.max_strands, self.points_per_strand)
        self.report({"INFO"}, f"nf_gpu: {report['curves']} hair curves on {report['body']}")
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


def menu_import(self, context):
    self.layout.operator(ImportNfGpuGroom.bl_idname, text="nf_gpu groom (export.json)")


def register():
    bpy.utils.register_class(ImportNfGpuGroom)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    bpy.utils.unregister_class(ImportNfGpuGroom)


def render_still(report, path, size=(800, 600), samples=32):
    """A Cycles still (PNG, or JPEG by the name) of the imported groom and body from the animal's
    front left, under a sky and a sun. A subset of the strands is widened by the share left out, so the coat covers as the whole
    groom would."""
    from mathutils import Vector
    scene = bpy.context.scene
    hair, body = bpy.data.objects["nf_gpu_fur"], bpy.data.objects[report["body"]]
    shown = max(1, report["curves"])
    radius = hair.data.attributes.get("radius")
    if radius is not None and report["strands_in_file"] > shown:
        r = np.empty(len(radius.data), np.float32)
        radius.data.foreach_get("value", r)
        radius.data.foreach_set("value", r * float(report["strands_in_file"]) / shown)
    corners = [body.matrix_world @ Vector(c) for c in body.bound_box]
    lo = Vector([min(c[i] for c in corners) for i in range(3)])
    hi = Vector([max(c[i] for c in corners) for i in range(3)])
    centre, extent = (lo + hi) / 2, max(hi - lo)
    camera = bpy.data.objects.new("nf_gpu camera", bpy.data.cameras.new("nf_gpu camera"))
    scene.collection.objects.link(camera)
    camera.data.lens = 50
    # glTF's +z forward is Blender's -y: the animal looks along -y, its left is +x.
    camera.location = centre + extent * Vector((0.8, -1.3, 0.42))
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    sun = bpy.data.objects.new("nf_gpu sun", bpy.data.lights.new("nf_gpu sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (0.7, 0.2, 0.6)
    scene.collection.objects.link(sun)
    scene.world = scene.world or bpy.data.worlds.new("nf_gpu sky")
    scene.world.use_nodes = True
    background = scene.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.55, 0.6, 0.68, 1)
    background.inputs["Strength"].default_value = 0.8
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # Debian's Cycles is built without OpenImageDenoise
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    jpeg = path.lower().endswith((".jpg", ".jpeg"))
    scene.render.image_settings.file_format = "JPEG" if jpeg else "PNG"
    if jpeg:
        scene.render.image_settings.quality = 90
    scene.render.filepath = os.path.abspath(path)
    bpy.ops.render.render(write_still=True)


def main(argv):
    import argparse
    parser = argparse.ArgumentParser(prog="blender -b -P nf_gpu_import.py --")
    parser.add_argument("folder", help="an nf_gpu export folder (WORK/export, or an edit's / a pose's --out)")
    parser.add_argument("--save", help="write the scene to this .blend")
    parser.add_argument("--max-strands", type=int, default=0, help="an even subset of the strands (0: all)")
    parser.add_argument("--points-per-strand", type=int, default=0, help="resample each strand (0: as in the file)")
    parser.add_argument("--report", help="write what was imported as JSON")
    parser.add_argument("--render", help="render a Cycles still (PNG, or JPEG for .jpg) of the groom and body to this file")
    parser.add_argument("--size", type=int, nargs=2, default=(800, 600), metavar=("W", "H"), help="the still's size in pixels")
    parser.add_argument("--samples", type=int, default=32, help="Cycles samples per pixel of the still")
    args = parser.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    report = import_groom(args.folder, args.max_strands, args.points_per_strand)
    print("nf_gpu import:", json.dumps(report))
    if args.report:
        with open(args.report, "w") as f:
            json.dump(report, f, indent=2)
    if args.render:
        render_still(report, args.render, tuple(args.size), args.samples)
    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save))


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
