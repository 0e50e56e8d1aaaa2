"""The baker's tables in Python, read by the Rust `formats` crate (the renderers' reader).

    import baker_formats as bf
    kind, metadata, arrays = bf.read_table("out/fitzpatrick/profiles.bkt")   # any .bkt
    t = bf.ProfileTable("out/fitzpatrick/profiles.bkt")
    e = t.lookup(skin_type="III", age_years=50, xi=0.5)
    rgb = t.rd_rgb(e, np.linspace(0, 5, 100))      # [100, 3], mm^-2, linear sRGB
    f = bf.BcsdfTable("out/fibers/silk/average.bcsdf")
    f.eval(wi, wo, variant=0)                      # float32 per channel, sr^-1

Layouts: formats/FORMAT.md. Arrays come from Rust as little-endian bytes and are wrapped with
numpy.frombuffer, so they hold exactly the Rust reader's values (dtype included). Errors raise
OSError (FileNotFoundError, PermissionError) for I/O and ValueError for everything else (bad
or corrupted files, unknown entries, variants out of range, non-finite directions), with the
Rust message.
"""

import json
from collections import namedtuple

import numpy as np

from . import _native

__all__ = ["read_table", "read_table_attrs", "ProfileTable", "BcsdfTable", "Gaussians", "direction", "__version__"]
__version__ = _native.__version__

_DTYPES = {"f64": np.dtype("<f8"), "f32": np.dtype("<f4"), "u32": np.dtype("<u4"), "u64": np.dtype("<u8")}

#: The sum-of-Gaussians fit of one profile: variances [n] (mm^2, ascending), weights [n, 3]
#: (linear sRGB), fit error [3]; Rd_c(r) ~ sum_i w[i, c] exp(-r^2 / 2 v_i) / (2 pi v_i).
Gaussians = namedtuple("Gaussians", ["variance_mm2", "weight_rgb", "error_rgb"])


def _array(dtype, shape, raw):
    return np.frombuffer(raw, dtype=_DTYPES[dtype]).reshape([int(n) for n in shape])


def _vec3(w, name):
    w = np.asarray(w, dtype=np.float64)
    if w.shape != (3,):
        raise ValueError(f"{name} must hold 3 numbers, got shape {w.shape}")
    return [float(x) for x in w]


def _directions(w, name):
    """Directions as a C-contiguous little-endian float64 array [n, 3]."""
    w = np.ascontiguousarray(w, dtype="<f8")
    if w.ndim != 2 or w.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {w.shape}")
    return w


def read_table(path):
    """Every array of any `.bkt` file: `(kind, metadata dict, {name: numpy array})`.

    Arrays are in file order, with the file's dtype (`<f8`, `<f4`, `<u4`, `<u8`) and shape.
    Attributes (units, descriptions) are in `read_table_attrs`.
    """
    kind, meta, arrays = _native.read_table(str(path))
    return kind, json.loads(meta), {name: _array(d, s, raw) for name, (d, s, raw, _) in arrays}


def read_table_attrs(path):
    """`{array name: {attribute: value}}` of a `.bkt` file (e.g. `units`)."""
    _, _, arrays = _native.read_table(str(path))
    return {name: dict(attrs) for name, (_, _, _, attrs) in arrays}


def direction(theta_rad, phi_rad):
    """Unit vector (cos θ cos φ, cos θ sin φ, sin θ) in the fiber frame (axis +z), as Rust."""
    return np.array(_native.direction_of(float(theta_rad), float(phi_rad)))


class ProfileTable:
    """A skin profile table (`profiles.bkt`, kind `skin_profiles`): `formats::ProfileTable`."""

    def __init__(self, path):
        self.path = str(path)
        self._t = _native.ProfileTableNative(self.path)
        self._entries = list(self._t.entries())
        self._metadata = None

    def __repr__(self):
        return f"ProfileTable({self.path!r}, {len(self._entries)} entries)"

    def __len__(self):
        return len(self._entries)

    def __contains__(self, entry):
        return entry in self._entries

    @property
    def entries(self):
        """Entry names in bake order, e.g. `typeIII_age50_xi0.5`."""
        return list(self._entries)

    @property
    def metadata(self):
        """Root metadata (provenance: spec, seed, photons, baker version, groups, ...)."""
        if self._metadata is None:
            self._metadata = json.loads(self._t.metadata_json())
        return self._metadata

    def attrs(self, entry):
        """The entry's group attributes (`age_years`, `skin_type`, `xi`, ...), as strings."""
        return dict(self._t.attrs(entry))

    def params(self, entry):
        """Every model input of the entry (`params_json` parsed)."""
        return json.loads(self._t.params_json(entry))

    def arrays(self, entry):
        """Every array of the entry, keyed without the `entry/` prefix: `r_mm` [nr] and
        `r_edges_mm` [nr+1] (the axes), `rd_rgb_per_mm2` [nr, 3], `rd_spectral_per_mm2`
        [nλ, nr], `lambda_nm`, `albedo_rgb`, `gaussians/weight_rgb`, ... (FORMAT.md)."""
        return {q: _array(d, s, raw) for q, (d, s, raw, _) in self._t.arrays(entry)}

    def array_attrs(self, entry):
        """`{quantity: {attribute: value}}` of the entry's arrays (`units`, `description`)."""
        return {q: dict(a) for q, (_, _, _, a) in self._t.arrays(entry)}

    def rd_rgb(self, entry, r_mm):
        """Rd(r) in linear sRGB, mm^-2: shape (3,) for a scalar r, r.shape + (3,) for an array.

        Linear in r between bin centres, the first bin's value below its centre, the last
        bin's value out to the outer edge, 0 beyond (and for NaN)."""
        r = np.asarray(r_mm, dtype="<f8")
        raw = self._t.rd_rgb(entry, np.ascontiguousarray(r).tobytes())
        return np.frombuffer(raw, dtype="<f8").reshape(r.shape + (3,))

    def albedo_rgb(self, entry):
        """Total diffuse reflectance per channel (linear sRGB), shape (3,)."""
        return np.array(self._t.albedo_rgb(entry), dtype=np.float64)

    def gaussians(self, entry):
        """The sum-of-Gaussians fit (`Gaussians`: variance_mm2 [n], weight_rgb [n, 3],
        error_rgb [3]); n = 0 and NaN errors if the table has no fit."""
        v, w, e = self._t.gaussians(entry)
        w = np.array(w, dtype=np.float64).reshape(len(v), 3)
        return Gaussians(np.array(v, dtype=np.float64), w, np.array(e, dtype=np.float64))

    def find(self, **query):
        """Names of the entries matching every key=value (group attributes such as
        `skin_type`, `age_years`, `xi`, or model inputs); numbers compare as numbers."""
        return list(self._t.find([(k, str(v)) for k, v in query.items()]))

    def lookup(self, **query):
        """The one entry matching `query` (see `find`); ValueError unless exactly one."""
        found = self.find(**query)
        if len(found) != 1:
            raise ValueError(f"{len(found)} entries match {query} (expected exactly one)")
        return found[0]


class BcsdfTable:
    """A fiber BCSDF table (`.bcsdf`): `formats::BcsdfTable`.

    Directions are 3-vectors in the fiber frame (axis +z; ωi towards the light, ωo away from
    the fiber); they need not be normalised. Per-channel values are float32, as stored."""

    def __init__(self, path):
        self.path = str(path)
        self._t = _native.BcsdfTableNative(self.path)
        self._directory = None

    def __repr__(self):
        d = self.directory
        return (
            f"BcsdfTable({self.path!r}, {len(d['wi_deg'])} stored directions, "
            f"{d['res_deg']} deg, variants {d['variants']}, channels {d['channels']})"
        )

    @property
    def directory(self):
        """The directory (FORMAT.md): `res_deg`, `n_theta`, `n_phi`, `variants`, `channels`,
        `dtype`, `keep_bits`, `metadata`, `chunks`, and as numpy arrays holding the reader's
        exact values `wi_deg` [n_wi, 2], `wi_map` [n_theta, n_phi] (uint32), `scale`,
        `albedo`, `albedo_se` [n_wi, n_variants, n_channels] (float32), `area_um` [n_phi]."""
        if self._directory is None:
            d = json.loads(self._t.directory_json())
            for name, (dt, shape, raw, _) in self._t.directory_arrays().items():
                d[name] = _array(dt, shape, raw)
            self._directory = d
        return self._directory

    @property
    def variants(self):
        return list(self.directory["variants"])

    @property
    def channels(self):
        return list(self.directory["channels"])

    @property
    def axes(self):
        """Bin centres in degrees: `theta_o_deg` [n_theta], `dphi_deg` [n_phi], `phi_deg`
        [n_phi] (azimuth of `area_um`), `theta_i_deg` and `phi_i_deg` [n_wi] (the stored
        incoming directions): the dimension scales of `f_normalised`."""
        return {k: np.array(v, dtype=np.float64) for k, v in self._t.axes().items()}

    def f_normalised(self):
        """Every stored slice decoded, float32 [n_wi, n_variants, n_channels, n_theta, n_phi],
        sr^-1: the values `eval_normalised` returns (axes: `axes`)."""
        d = self.directory
        shape = (len(d["wi_deg"]), len(d["variants"]), len(d["channels"]), d["n_theta"], d["n_phi"])
        return np.frombuffer(self._t.f_normalised(), dtype="<f4").reshape(shape)

    def eval(self, wi, wo, variant=0):
        """f(ωi, ωo) = Λ(ωi)·f̂(ωi, ωo), sr^-1, float32 per channel."""
        return np.array(self._t.eval(_vec3(wi, "wi"), _vec3(wo, "wo"), int(variant)), dtype=np.float32)

    def eval_normalised(self, wi, wo, variant=0):
        """f̂(ωi, ωo), sr^-1 (sum of f̂ ΔΩ = 1 over the bins), float32 per channel."""
        return np.array(
            self._t.eval_normalised(_vec3(wi, "wi"), _vec3(wo, "wo"), int(variant)), dtype=np.float32
        )

    def pdf(self, wi, wo, variant=0):
        """Density of `sample` at ωo, sr^-1."""
        return self._t.pdf(_vec3(wi, "wi"), _vec3(wo, "wo"), int(variant))

    def sample(self, wi, u1, u2, variant=0):
        """`(wo, pdf)` drawn with u1, u2 in [0, 1], or None where the variant scatters nothing."""
        s = self._t.sample(_vec3(wi, "wi"), float(u1), float(u2), int(variant))
        return None if s is None else (np.array(s[0], dtype=np.float64), s[1])

    def albedo(self, wi, variant=0):
        """Directional albedo Λ(ωi), float32 per channel."""
        return np.array(self._t.albedo(_vec3(wi, "wi"), int(variant)), dtype=np.float32)

    # Batched queries (one native call for n directions, spread over the cores): the
    # Mitsuba plugin (baker_formats.mitsuba) and anything else that evaluates many at once.

    def eval_many(self, wi, wo, variant=0):
        """`eval` for arrays of directions wi, wo [n, 3]: float32 [n, n_channels]."""
        a, b = _directions(wi, "wi"), _directions(wo, "wo")
        raw = self._t.eval_batch(a.tobytes(), b.tobytes(), int(variant))
        return np.frombuffer(raw, dtype="<f4").reshape(len(a), len(self.channels))

    def pdf_many(self, wi, wo, variant=0):
        """`pdf` for arrays of directions wi, wo [n, 3]: float64 [n], sr^-1."""
        a, b = _directions(wi, "wi"), _directions(wo, "wo")
        return np.frombuffer(self._t.pdf_batch(a.tobytes(), b.tobytes(), int(variant)), dtype="<f8")

    def eval_pdf_many(self, wi, wo, variant=0):
        """`(eval_many, pdf_many)` in one pass."""
        a, b = _directions(wi, "wi"), _directions(wo, "wo")
        f, p = self._t.eval_pdf_batch(a.tobytes(), b.tobytes(), int(variant))
        return (np.frombuffer(f, dtype="<f4").reshape(len(a), len(self.channels)),
                np.frombuffer(p, dtype="<f8"))

    def sample_many(self, wi, u, variant=0):
        """`sample` for directions wi [n, 3] and uniform numbers u [n, 2] in [0, 1]:
        `(wo [n, 3], pdf [n], f [n, n_channels])` with f = eval(wi, wo); where the variant
        scatters nothing, wo = 0 and pdf = f = 0."""
        a = _directions(wi, "wi")
        u = np.ascontiguousarray(u, dtype="<f8")
        if u.shape != (len(a), 2):
            raise ValueError(f"u must have shape ({len(a)}, 2), got {u.shape}")
        wo, pdf, f = self._t.sample_batch(a.tobytes(), u.tobytes(), int(variant))
        return (np.frombuffer(wo, dtype="<f8").reshape(len(a), 3), np.frombuffer(pdf, dtype="<f8"),
                np.frombuffer(f, dtype="<f4").reshape(len(a), len(self.channels)))

    def projected_area(self, w):
        """Projected area of a unit length of fiber seen from ω, µm (width at φ × cos θ)."""
        return self._t.projected_area(_vec3(w, "w"))

    def area_um(self, w):
        """Projected width per unit length seen from the azimuth of ω, µm (no cos θ)."""
        return self._t.area_um(_vec3(w, "w"))
