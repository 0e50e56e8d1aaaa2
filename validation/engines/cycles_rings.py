"""Blender/Cycles half of check_engine_profiles.py; runs in the bpy venv:

    target/bpy-venv/bin/python validation/engines/cycles_rings.py JOB.json

JOB.json (written by check_engine_profiles.py) names, per entry, the `baker export --to blender`
script, the material (entry name) it creates, the ring edges and the slab. For each entry the
scene (millimetres: unit_settings.scale_length = 0.001, so the export's Subsurface Scale is 1)
is a closed box slab with top face at z = 0 carrying the exported material, one emissive ring
mesh per annulus at z = eps, each in its own light group, and an orthographic camera straight
above the origin whose film sees a square of side camera_footprint_mm. One render per seed
writes a multilayer EXR whose light-group passes (Combined_<ring>) hold the radiance with each
ring alone lit; check_engine_profiles.py reads them.

The export script itself sets up the material (runpy, as `blender --python` would run it).
"""

import json
import math
import os
import runpy
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rings import ring_polygon  # noqa: E402


def reset_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.unit_settings.system = "METRIC"
    scene.unit_settings.scale_length = 0.001  # one Blender unit = 1 mm
    scene.render.engine = "CYCLES"
    cyc = scene.cycles
    cyc.device = "CPU"
    cyc.use_adaptive_sampling = False
    cyc.use_denoising = False
    cyc.pixel_filter_type = "BOX"
    cyc.filter_width = 1.0
    cyc.sample_clamp_direct = 0.0
    cyc.sample_clamp_indirect = 0.0
    cyc.max_bounces = 64
    cyc.diffuse_bounces = 64
    cyc.glossy_bounces = 64
    cyc.transmission_bounces = 64
    cyc.volume_bounces = 64
    cyc.transparent_max_bounces = 64
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    return scene


def add_mesh(name, verts, faces):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_slab(half, thick, material):
    v = [
        (x, y, z)
        for z in (-thick, 0.0)
        for y in (-half, half)
        for x in (-half, half)
    ]
    # Outward-facing quads of the box (vertex index = x + 2 y + 4 z).
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    obj = add_mesh("slab", v, faces)
    obj.data.materials.append(material)
    return obj


def emission_material(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    em = nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    em.inputs["Strength"].default_value = 1.0
    out = nodes.new("ShaderNodeOutputMaterial")
    mat.node_tree.links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat


def white_diffuse():
    mat = bpy.data.materials.new("white_diffuse")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    d = nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    out = nodes.new("ShaderNodeOutputMaterial")
    mat.node_tree.links.new(d.outputs["BSDF"], out.inputs["Surface"])
    return mat


def add_rings(edges, eps):
    scene = bpy.context.scene
    layer = scene.view_layers[0]
    em = emission_material("ring_emission")
    names = []
    for k, (r_in, r_out) in enumerate(zip(edges[:-1], edges[1:])):
        verts, tris = ring_polygon(r_in, r_out, eps)
        name = f"ring{k:02d}"
        obj = add_mesh(name, verts, tris)
        obj.data.materials.append(em)
        # Invisible to the camera and to glossy rays (the camera looks through the rings, and
        # the skin's specular layer must not reflect them straight up into it); visible to the
        # diffuse, transmission and shadow rays that carry their light into the slab.
        obj.visible_camera = False
        obj.visible_glossy = False
        layer.lightgroups.add(name=name)
        obj.lightgroup = name
        names.append(name)
    return names


def add_camera(foot, pixels, height):
    scene = bpy.context.scene
    cam_data = bpy.data.cameras.new("cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = foot
    cam_data.clip_start = height * 0.5
    cam_data.clip_end = height * 2.0
    cam = bpy.data.objects.new("cam", cam_data)
    cam.location = (0.0, 0.0, height)  # default orientation looks down -z
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.render.resolution_x = pixels
    scene.render.resolution_y = pixels
    scene.render.resolution_percentage = 100
    img = scene.render.image_settings
    if hasattr(img, "media_type"):  # Blender >= 5.0
        img.media_type = "MULTI_LAYER_IMAGE"
    img.file_format = "OPEN_EXR_MULTILAYER"
    img.color_depth = "32"
    img.exr_codec = "NONE"


def render(path, spp, seed):
    scene = bpy.context.scene
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)


def build(geom, material_fn):
    scene = reset_scene()
    mat = material_fn()
    add_slab(geom["slab_half_mm"], geom["slab_thick_mm"], mat)
    names = add_rings(geom["edges_mm"], geom["eps_mm"])
    add_camera(geom["camera_footprint_mm"], geom["pixels"], 10.0 * geom["slab_half_mm"])
    return scene, names


def main():
    job = json.load(open(sys.argv[1], encoding="utf-8"))
    done = {}
    for run in job["runs"]:
        geom = run["geometry"]
        t0 = time.perf_counter()

        def exported_material():
            # The export script, run as Blender would run it; it reads the scene's unit scale.
            runpy.run_path(run["blender_script"], run_name="__main__")
            mat = bpy.data.materials.get(run["material"])
            if mat is None:
                raise SystemExit(f"error: {run['blender_script']} made no material {run['material']!r}")
            bsdf = [n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"]
            if len(bsdf) != 1:
                raise SystemExit(f"error: material {run['material']!r} has {len(bsdf)} Principled BSDFs")
            seen["subsurface_method"] = bsdf[0].subsurface_method
            return mat

        names = None
        files = []
        seen = {}
        for seed in job["seeds"]:
            # Rebuilt per seed: read_factory_settings drops the material the export made.
            _, names = build(geom, exported_material)
            path = os.path.join(job["workdir"], f"{run['key']}_seed{seed}.exr")
            render(path, job["spp"], seed)
            files.append(path)
        # Calibration: white Lambertian slab, one disk ring (radius = slab_half) so wide that the
        # gap eps does not matter: its pixel radiance is the rings' radiance Le.
        cal_geom = dict(geom, edges_mm=[0.0, geom["slab_half_mm"]])
        build(cal_geom, white_diffuse)
        cal = os.path.join(job["workdir"], f"{run['key']}_calibration.exr")
        render(cal, 4 * job["spp"], 0)
        done[run["key"]] = {
            "ring_names": names,
            "seed_files": files,
            "calibration_file": cal,
            "seconds": time.perf_counter() - t0,
            "blender_version": bpy.app.version_string,
            "subsurface_method": seen["subsurface_method"],
        }
    tmp = job["result"] + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(done, f, indent=1)
    os.replace(tmp, job["result"])


if __name__ == "__main__":
    main()
