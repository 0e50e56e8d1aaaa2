"""Runs inside Blender's Python (bpy): executes a `baker export --to blender` script unchanged,
reads back the materials it made, and renders a small sphere (skin) or a patch of hair curves
(fiber) with each, in Cycles on the CPU.

    target/bpy-venv/bin/python validation/blender/render_spheres.py EXPORT.py OUT_DIR \
        [--size 64] [--samples 16] [--kind skin|fiber]

Writes OUT_DIR/<material>.exr (linear, the render) and OUT_DIR/report.json: per material the
node values Blender holds (Subsurface Method, Base Color, Subsurface Radius/Scale, IOR, ... or
the hair inputs) and the render's mean linear RGB over the object's pixels. The scene: a unit
sphere of radius SPHERE_M = 3 cm (a cheek's curvature; the exported Subsurface Scale turns the
radii in mm into scene units) or 40 parallel hair curves, one sun light at 45°, black world, a camera
looking down -z. validation/check_blender.py and validation/blender/contact_sheet.py use it.
"""

import argparse
import json
import math
import runpy
import sys
from pathlib import Path

import bpy
import numpy as np


def reset_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("black")
    world.color = (0.0, 0.0, 0.0)
    scene.world = world
    return scene


def setup_render(scene, size, samples, seed=1):
    scene.render.resolution_x = size
    scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.cycles.samples = samples
    scene.cycles.seed = seed
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.max_bounces = 8
    scene.render.film_transparent = True
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"


SPHERE_M = 0.03


def add_camera_and_light(scene, distance=3.2, ortho_scale=2.3):
    cam_data = bpy.data.cameras.new("cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = ortho_scale
    cam_data.clip_start = 0.01 * distance
    cam_data.clip_end = 10.0 * distance
    cam = bpy.data.objects.new("cam", cam_data)
    cam.location = (0.0, 0.0, distance)
    scene.collection.objects.link(cam)
    scene.camera = cam
    sun_data = bpy.data.lights.new("sun", type="SUN")
    sun_data.energy = 3.0
    sun = bpy.data.objects.new("sun", sun_data)
    sun.rotation_euler = (math.radians(45.0), 0.0, math.radians(30.0))
    scene.collection.objects.link(sun)


def add_sphere(scene):
    mesh = bpy.data.meshes.new("sphere")
    import bmesh

    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=48, v_segments=24, radius=SPHERE_M)
    bm.to_mesh(mesh)
    bm.free()
    for p in mesh.polygons:
        p.use_smooth = True
    ob = bpy.data.objects.new("sphere", mesh)
    scene.collection.objects.link(ob)
    return ob


def add_hair_patch(scene, n=40):
    """n parallel straight hair curves along +x in the z = 0 plane (Curves object)."""
    curves = bpy.data.hair_curves.new("fibers")
    curves.add_curves([2] * n)
    pos = curves.attributes["position"].data
    radius = curves.attributes.get("radius") or curves.attributes.new("radius", "FLOAT", "POINT")
    for i in range(n):
        y = -1.0 + 2.0 * (i + 0.5) / n
        pos[2 * i].vector = (-1.0, y, 0.0)
        pos[2 * i + 1].vector = (1.0, y, 0.0)
        radius.data[2 * i].value = 0.9 / n
        radius.data[2 * i + 1].value = 0.9 / n
    ob = bpy.data.objects.new("fibers", curves)
    scene.collection.objects.link(ob)
    return ob


def render_to(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(str(path))
    w, h = img.size
    px = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, 4)
    bpy.data.images.remove(img)
    return px


def value(socket):
    v = socket.default_value
    try:
        return [float(x) for x in v]
    except TypeError:
        return float(v)


def skin_nodes(mat):
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    out = {"subsurface_method": bsdf.subsurface_method}
    for name in ["Base Color", "Subsurface Weight", "Subsurface Radius", "Subsurface Scale",
                 "IOR", "Subsurface IOR", "Subsurface Anisotropy"]:
        # All sockets by name: `name in bsdf.inputs` skips those the method hides.
        socket = next((s for s in bsdf.inputs if s.name == name), None)
        if socket is not None:
            out[name] = value(socket)
    out["linked_to_output"] = any(
        link.from_node == bsdf and link.to_node.type == "OUTPUT_MATERIAL"
        for link in mat.node_tree.links)
    return out


def hair_nodes(mat):
    hair = next(n for n in mat.node_tree.nodes if n.type == "BSDF_HAIR_PRINCIPLED")
    out = {"parametrization": hair.parametrization}
    if "model" in hair.bl_rna.properties:
        out["model"] = hair.model
    for name in ["Absorption Coefficient", "Roughness", "Radial Roughness", "Coat", "IOR",
                 "Offset", "Random Roughness"]:
        if name in hair.inputs:
            out[name] = value(hair.inputs[name])
    return out


def run_export(script):
    """Runs the exported script as `blender --python` would (as __main__)."""
    before = set(bpy.data.materials.keys())
    runpy.run_path(str(script), run_name="__main__")
    return [m for m in bpy.data.materials.keys() if m not in before]


def main(argv):
    ap = argparse.ArgumentParser()
    ap.add_argument("script")
    ap.add_argument("out")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--kind", choices=["skin", "fiber"], default="skin")
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    scene = reset_scene()
    setup_render(scene, a.size, a.samples)
    if a.kind == "skin":
        add_camera_and_light(scene, 3.2 * SPHERE_M, 2.3 * SPHERE_M)
    else:
        add_camera_and_light(scene)
    ob = add_sphere(scene) if a.kind == "skin" else add_hair_patch(scene)
    if a.kind == "fiber":
        # The fiber export assigns its material to the selected objects.
        bpy.context.view_layer.objects.active = ob
        ob.select_set(True)
    made = run_export(a.script)
    report = {"blender_version": list(bpy.app.version), "size": a.size,
              "samples": a.samples, "materials": {}}
    for name in made:
        mat = bpy.data.materials[name]
        if a.kind == "fiber":
            assigned = bool(ob.data.materials) and ob.data.materials[0] == mat
        else:
            ob.data.materials.clear()
            ob.data.materials.append(mat)
            assigned = True
        nodes = skin_nodes(mat) if a.kind == "skin" else hair_nodes(mat)
        safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name)
        px = render_to(scene, out / f"{safe}.exr")
        mask = px[..., 3] > 0.5
        rgb = px[..., :3][mask]
        report["materials"][name] = {
            "nodes": nodes,
            "assigned": assigned,
            "image": f"{safe}.exr",
            "object_pixels": int(mask.sum()),
            "finite": bool(np.isfinite(px).all()),
            "mean_rgb": rgb.mean(axis=0).tolist() if len(rgb) else [0.0, 0.0, 0.0],
        }
    (out / "report.json").write_text(json.dumps(report, indent=1))
    print(f"render_spheres: {len(made)} materials → {out / 'report.json'}")


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
