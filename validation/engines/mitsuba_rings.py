"""Mitsuba 3 half of check_engine_profiles.py: the exported homogeneous medium in a slab, lit by
Lambertian ring emitters lying just above its surface (null BSDF: transparent, emitting
downwards only), seen by an orthographic camera looking
straight down at the ring centre (the reciprocal of a normally incident pencil beam; the
derivation is in check_engine_profiles.py's docstring).

One scene per entry; each ring is rendered alone by setting the other rings' radiance to 0
(`mi.traverse`), with several independent seeds for the Monte Carlo standard error.
"""

import os
import time
import xml.etree.ElementTree as ET

import numpy as np

from rings import ring_polygon, write_ply


def exported_medium(xml_path, entry_id):
    """The `<bsdf type="null" id="ID_boundary">` and `<medium id="ID">` elements of a
    `baker export --to mitsuba` file, serialised back to XML text, unchanged."""
    root = ET.parse(xml_path).getroot()
    bsdf = root.find(f"./bsdf[@id='{entry_id}_boundary']")
    medium = root.find(f"./medium[@id='{entry_id}']")
    if bsdf is None or medium is None:
        raise SystemExit(f"error: {xml_path} has no medium/boundary with id {entry_id!r}")
    return ET.tostring(bsdf, encoding="unicode"), ET.tostring(medium, encoding="unicode")


# Scene length unit: micrometres. Mitsuba's single-precision variants offset spawned rays by
# about (1 + max |p|) * 9e-5 scene units (math::RayEpsilon); in micrometres that is 9e-5 of the
# distance from the origin, so a ring at radius a can float 1e-3 a above the surface (11
# offsets) while the innermost rings, at 0.01-0.05 mm, sit 10-50 nm above it. In millimetres
# the constant 9e-5 mm floor forced a gap of a few micrometres everywhere, which blurred the
# innermost rings of the dark entries (mean free paths of 0.03 mm) by 5-10 % L1. Higher rings
# (1e-2 a) lit 2-4 % too much: their light spills at grazing incidence, which reflects more.
UNIT_PER_MM = 1000.0
RING_HEIGHT_REL = 1e-3  # ring height above the surface / the ring's outer radius


def micrometre_medium(medium_xml):
    """The exported medium with its `scale` (1/mm) converted to 1/micrometre, the one change
    the export's own comment prescribes for other scene units ("multiply scale by 1000 for a
    scene in metres")."""
    el = ET.fromstring(medium_xml)
    sc = el.find("./float[@name='scale']")
    if sc is None:
        raise SystemExit("error: exported medium has no <float name=\"scale\">")
    sc.set("value", repr(float(sc.get("value")) / UNIT_PER_MM))
    return ET.tostring(el, encoding="unicode")


def ring_ply(path, r_in_mm, r_out_mm):
    """Ring mesh in micrometres at height RING_HEIGHT_REL * r_out."""
    u = UNIT_PER_MM
    verts, tris = ring_polygon(r_in_mm * u, r_out_mm * u, RING_HEIGHT_REL * r_out_mm * u)
    write_ply(path, verts, tris)
    return path


def scene_xml(geom, ring_files, interior_xml=None, boundary_xml=None, diffuse_white=False):
    """Scene in micrometres: slab top at z = 0, rings just above it, camera above the origin."""
    half = geom["slab_half_mm"] * UNIT_PER_MM
    thick = geom["slab_thick_mm"] * UNIT_PER_MM
    foot = geom["camera_footprint_mm"] * UNIT_PER_MM
    px = geom["pixels"]
    if diffuse_white:
        slab_bsdf = '<bsdf type="diffuse"><rgb name="reflectance" value="1, 1, 1"/></bsdf>'
        interior = ""
        defs = ""
    else:
        slab_bsdf = f'<ref id="{ET.fromstring(boundary_xml).get("id")}"/>'
        interior = f'<ref name="interior" id="{ET.fromstring(interior_xml).get("id")}"/>'
        defs = boundary_xml + "\n" + micrometre_medium(interior_xml)
    rings = "\n".join(
        f'<shape type="ply" id="ring{k}"><string name="filename" value="{path}"/>'
        f'<boolean name="face_normals" value="true"/><bsdf type="null"/>'
        f'<emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>'
        for k, path in enumerate(ring_files)
    )
    h = 10.0 * max(half, thick)
    return f"""<scene version="3.0.0">
<integrator type="volpathmis"><integer name="max_depth" value="-1"/></integrator>
<sensor type="orthographic">
  <transform name="to_world">
    <scale x="{foot / 2}" y="{foot / 2}" z="1"/>
    <lookat origin="0, 0, {h}" target="0, 0, 0" up="0, 1, 0"/>
  </transform>
  <float name="near_clip" value="{h * 0.5}"/>
  <float name="far_clip" value="{h * 2.0}"/>
  <film type="hdrfilm"><integer name="width" value="{px}"/><integer name="height" value="{px}"/>
    <rfilter type="box"/><string name="pixel_format" value="rgb"/></film>
  <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
</sensor>
{defs}
<shape type="cube">
  <transform name="to_world"><scale x="{half}" y="{half}" z="{thick / 2}"/>
    <translate z="{-thick / 2}"/></transform>
  {slab_bsdf}
  {interior}
</shape>
{rings}
</scene>"""


def render_rings(mi, xml_text, n_rings, spp, seeds):
    """Mean pixel radiance (RGB) with ring k alone lit, for every k and seed:
    array (n_rings, len(seeds), 3)."""
    scene = mi.load_string(xml_text)
    params = mi.traverse(scene)
    keys = [f"ring{k}.emitter.radiance.value" for k in range(n_rings)]
    for key in keys:
        if key not in params:
            raise SystemExit(f"error: Mitsuba scene has no parameter {key!r}")
    out = np.zeros((n_rings, len(seeds), 3))
    for k in range(n_rings):
        for j, key in enumerate(keys):
            params[key] = mi.Color3f(1.0 if j == k else 0.0)
        params.update()
        for s_i, seed in enumerate(seeds):
            img = np.array(mi.render(scene, spp=spp, seed=seed))
            out[k, s_i] = img[..., :3].reshape(-1, 3).mean(axis=0)
    return out


def run(job, workdir):
    """Renders every entry of `job` (see check_engine_profiles.py); returns
    {entry: {"ring_radiance": (rings, seeds, 3) list, "seconds": s}} plus the calibration."""
    import mitsuba as mi

    mi.set_variant(job.get("mitsuba_variant", "scalar_rgb"))
    os.makedirs(workdir, exist_ok=True)
    results = {}
    for ent in job["entries"]:
        geom = ent["geometry"]
        files = [
            ring_ply(os.path.join(workdir, f"{ent['id']}_ring{k}.ply"), r_in, r_out)
            for k, (r_in, r_out) in enumerate(zip(geom["edges_mm"][:-1], geom["edges_mm"][1:]))
        ]
        boundary, medium = exported_medium(job["mitsuba_xml"], ent["id"])
        t0 = time.perf_counter()
        rad = render_rings(
            mi, scene_xml(geom, files, medium, boundary), len(files), job["spp"], job["seeds"]
        )
        # Calibration, same slab: a white Lambertian slab (albedo 1, Rd = delta at r = 0) under
        # one disk of radius slab_half (irradiance fraction at its centre
        # 1 / (1 + RING_HEIGHT_REL^2) = 0.9999) returns the rings' radiance Le.
        cal_file = ring_ply(os.path.join(workdir, f"{ent['id']}_calibration.ply"), 0.0, geom["slab_half_mm"])
        cal = render_rings(
            mi, scene_xml(geom, [cal_file], diffuse_white=True), 1, 4 * job["spp"], job["seeds"][:1]
        )
        results[ent["id"]] = {
            "ring_radiance": rad.tolist(),
            "calibration_radiance": cal[0, 0].tolist(),
            "seconds": time.perf_counter() - t0,
        }
    return results
