# Run inside Blender (blender -b --python-exit-code 1 -P check_import.py -- EXPORT_DIR ADDON):
# Blender's own importers read body.glb (armature with the export's joints; a posed bone moves
# vertices) and fur.obj (one edge per strand segment), and the add-on builds hair curves attached to
# the body with the .hair file's curve and point counts. Any failed check raises: exit code 1.
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
counts, points, _ = addon.read_hair(os.path.join(folder, "fur.hair"))
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
