"""Ring geometry shared by the Mitsuba and Cycles renders of check_engine_profiles.py.

Plain Python + numpy (no renderer import), so the bpy venv (numpy < 2) and the main
environment (numpy 2) can both import it.
"""

import math

SEGMENTS = 256  # polygon sides of each ring; area deficit 1 - sin(2pi/n)/(2pi/n) = 1.0e-4


def ring_polygon(r_in, r_out, z, segments=SEGMENTS):
    """Vertices and triangles of the annulus r_in <= r <= r_out (r_in = 0: a disk) at height z,
    wound so the face normal points down (-z): the emitting side faces the slab below.

    The polygon's vertices lie on circles of radius r * k with k chosen so the polygon's area
    equals the circle's (k^2 = (2 pi / n) / sin(2 pi / n)), so ring energies match the exact
    annuli the baked table is integrated over."""
    n = segments
    k = math.sqrt((2 * math.pi / n) / math.sin(2 * math.pi / n))
    ang = [2 * math.pi * i / n for i in range(n)]
    outer = [(r_out * k * math.cos(a), r_out * k * math.sin(a), z) for a in ang]
    if r_in <= 0:
        verts = [(0.0, 0.0, z)] + outer
        # (centre, next, this): clockwise seen from +z, so the normal is -z.
        tris = [(0, 1 + (i + 1) % n, 1 + i) for i in range(n)]
        return verts, tris
    inner = [(r_in * k * math.cos(a), r_in * k * math.sin(a), z) for a in ang]
    verts = inner + outer
    tris = []
    for i in range(n):
        j = (i + 1) % n
        a_i, a_j, b_i, b_j = i, j, n + i, n + j
        tris.append((a_i, b_j, b_i))
        tris.append((a_i, a_j, b_j))
    return verts, tris


def write_ply(path, verts, tris):
    """ASCII PLY (Mitsuba's `ply` shape reads it)."""
    with open(path, "w", encoding="ascii") as f:
        f.write("ply\nformat ascii 1.0\n")
        f.write(f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n")
        f.write(f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n")
        for v in verts:
            f.write(f"{v[0]:.9g} {v[1]:.9g} {v[2]:.9g}\n")
        for t in tris:
            f.write(f"3 {t[0]} {t[1]} {t[2]}\n")
