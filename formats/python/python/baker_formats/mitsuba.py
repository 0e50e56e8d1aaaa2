"""A Mitsuba 3 BSDF plugin that renders a baked fiber table (`.bcsdf`) through the Rust reader.

    import mitsuba as mi
    mi.set_variant("scalar_rgb")          # or "llvm_ad_rgb" (see "Variants" below)
    from baker_formats import mitsuba as bm
    bm.register()                         # adds the plugin "baker_bcsdf"

    <bsdf type="baker_bcsdf">
        <string name="filename" value="out/fibers/silk"/>   <!-- a .bcsdf file or an entry folder -->
        <string name="variant" value="undyed"/>             <!-- name or index; default 0 -->
        <string name="section" value="average"/>            <!-- entry folders only -->
        <vector name="up" x="0" y="0" z="1"/>               <!-- optional, world space -->
    </bsdf>

Attach it to a `bsplinecurve` shape (Mitsuba's fiber primitive, as its own `hair` plugin is
used). Not `linearcurve`: in Mitsuba 3.9.1 its hits carry no tangent (dp_du = dp_dv = 0) and a
shading frame whose t is arbitrary about the normal, so no BSDF (`hair` included) can find the
fiber axis there; the plugin warns once when it meets such a hit. `register()` must be called after `mi.set_variant` and again after a
change of variant.

Parameters
----------
``filename``
    A `.bcsdf` file, or the folder of one baked entry. A folder holds either one
    ``section-00.bcsdf`` (a single cross-section) or several ``section-NN.bcsdf`` and their
    ``average.bcsdf`` (``sections: N`` in the spec).
``section``
    Folders only: ``average`` (the default where the folder has one: the mean over the seeded
    cross-sections, what a yarn of many fibers shows), or an integer NN for ``section-NN.bcsdf``.
    A folder with a single section needs none. Naming a section together with a file is an error.
``variant``
    The dye variant: its name as in the table (``undyed``, ``orange_reactive@1%``) or its index;
    default 0. An unknown name lists the table's variants.
``up``
    The world direction that fixes the cross-section's orientation about the fiber axis (the
    table's +x axis is ``up`` made perpendicular to the tangent); default (0, 0, 1). Only
    tables of non-round sections (cotton, silk, trilobal) depend on it. Where a fiber runs
    parallel to ``up`` (within 0.06 deg) the local surface normal takes its place.

Frame
-----
A `bsplinecurve` hit has the shading frame s (around the fiber), t = dp_dv/|dp_dv| = the
curve's tangent (from the first control point to the last), n = the surface normal,
right-handed (Mitsuba 3.9.1, checked by validation/check_mitsuba_bcsdf.py), and `si.wi`, `wo`
in it: the local frame of `hair.cpp` (tangent local y, normal local z; baker/src/export/chiang/
frame.rs). The table frame (formats/FORMAT.md: fiber axis +z, θ = asin(ω·z), φ = atan2(ω·y,
ω·x)) is built right-handed from it: z_table = t, x_table = ``up`` made perpendicular to t,
y_table = z_table × x_table. θ is therefore Mitsuba's sin θ = ω·y, the same as the Chiang
export's; φ turns the right-handed way about the tangent, so a section's orientation is the
one the tracer used (the Chiang export's (x, z, y) map is the mirror image, which only
φ-symmetric models can afford). The tangent's sign matters for tables with cuticle scales
(wool): the scales point to the curve's direction.

What a hit returns (the convention)
-----------------------------------
A table stores the far-field f(ωi, ωo) = Λ(ωi)·f̂(ωi, ωo): of the power a unit length of fiber
intercepts from ωi (towards the light), the fraction per steradian leaving along ωo, averaged
over the fiber's width (thesis §5.5, Eq. 5.25; FORMAT.md). The radiance of a fiber seen from
ωc is then L(ωc) = ∫ f(ωc, ωl)·L(ωl) dωl (the reciprocity A(ωi)·f(ωi, ωo) = A(ωo)·f(ωo, ωi)
turns the intercepted power into radiance per projected area; baker/src/export/chiang/mod.rs
"Far field and the table"). Mitsuba's `BSDF::eval` returns the BSDF times the cosine
foreshortening, the quantity the integrator multiplies by the incident radiance and divides by
the pdf; so the plugin returns, like `hair.cpp` (whose Chiang S̄ has no cosine factor either),

    eval(si.wi, wo) = f(ωi = si.wi, ωo = wo),       pdf = the table's sampling density,

with si.wi (towards the camera: the table's ωi) and wo (towards the light: the table's ωo) in
the table frame, at every hit point alike: the width average is done by the table, the curve
only says where the fiber is. Camera rays hit a curve uniformly over its projected width, so
the pixel of a fiber gets ∫ f L dωl: the far-field radiance. Mitsuba's curves are not hit from
inside (a ray leaving a curve's surface inwards passes through it), so a path scatters once
per fiber, as the table's far field assumes. With an undyed table (Λ = 1) every path keeps its
weight and a uniform environment returns itself: validation/check_mitsuba_bcsdf.py renders
that white furnace. Not modelled: a fiber whose width is not small against the pixel or the
fiber spacing (the far field needs both), and a section's projected width (a round curve of
the shape's radius intercepts the light, whatever the table's section).

Variants
--------
`scalar_rgb` (one native call per query) and the JIT variants `llvm_ad_rgb`/`cuda_ad_rgb`
(one batched native call, over the cores, per wavefront). The JIT variants need evaluated
loops and calls, because the table is evaluated outside Dr.Jit's traced kernels:
`dr.set_flag(dr.JitFlag.SymbolicLoops, False)`, `dr.set_flag(dr.JitFlag.SymbolicCalls,
False)` (`enable_jit_evaluation()` does it). Not differentiable. Tables must have the
channels R, G, B (`channels: rgb` in the spec) or one channel (grey).
"""

import math
import os
import re
import warnings

import numpy as np

from . import BcsdfTable

PLUGIN = "baker_bcsdf"

_SECTION = re.compile(r"^section-(\d+)\.bcsdf$")


def resolve_path(filename, section=None):
    """The `.bcsdf` file that ``filename`` and ``section`` name (see the module docs)."""
    path = os.fspath(filename)
    if os.path.isfile(path):
        if section is not None:
            raise ValueError(f"{PLUGIN}: 'section' = {section!r} needs a folder, {path!r} is a file")
        return path
    if not os.path.isdir(path):
        raise ValueError(f"{PLUGIN}: 'filename' = {path!r} is neither a .bcsdf file nor an entry folder")
    sections = sorted(int(m.group(1)) for m in map(_SECTION.match, os.listdir(path)) if m)
    average = os.path.join(path, "average.bcsdf")
    choices = (["average"] if os.path.isfile(average) else []) + [str(s) for s in sections]
    if not choices:
        raise ValueError(f"{PLUGIN}: folder {path!r} holds no section-NN.bcsdf or average.bcsdf")
    if section is None:
        if os.path.isfile(average):
            return average
        if len(sections) == 1:
            return os.path.join(path, f"section-{sections[0]:02d}.bcsdf")
        raise ValueError(f"{PLUGIN}: folder {path!r} holds several sections and no average; "
                         f"set 'section' to one of {choices}")
    s = str(section).strip()
    if s == "average" and os.path.isfile(average):
        return average
    if s.isdigit() and int(s) in sections:
        return os.path.join(path, f"section-{int(s):02d}.bcsdf")
    raise ValueError(f"{PLUGIN}: no section {section!r} in {path!r} (choices: {choices})")


def resolve_variant(table, variant):
    """Index of ``variant`` (a name or an index) in ``table``."""
    names = table.variants
    if isinstance(variant, str) and not variant.strip().lstrip("-").isdigit():
        if variant not in names:
            raise ValueError(f"{PLUGIN}: no variant {variant!r} in {table.path} (variants: {names})")
        return names.index(variant)
    i = int(variant)
    if not 0 <= i < len(names):
        raise ValueError(f"{PLUGIN}: variant {i} out of range: {table.path} has {len(names)} ({names})")
    return i


# ----- frames (numpy, n directions at once; the scalar variant passes n = 1) -----

def _local_axes(s, t, n, up):
    """Table axes x, y, z in local coordinates [m, 3] each, for shading frames s, t, n [m, 3]
    (world) and the world vector ``up``. A frame of zeros (Mitsuba's chi2 adapter builds its
    SurfaceInteraction with dr.zeros) counts as the identity."""
    degenerate = (n * n).sum(1) < 0.25
    eye = np.eye(3)
    s, t, n = (np.where(degenerate[:, None], eye[k], a) for k, a in enumerate((s, t, n)))
    up_l = np.stack([(s * up).sum(1), (t * up).sum(1), (n * up).sum(1)], 1)
    z = np.zeros_like(up_l)
    z[:, 1] = 1.0                                   # the tangent t is local y
    x = up_l.copy()
    x[:, 1] = 0.0                                   # up made perpendicular to the tangent
    norm = np.sqrt((x * x).sum(1))
    parallel = norm < 1e-3
    x = np.where(parallel[:, None], np.array([0.0, 0.0, 1.0]), x / np.where(parallel, 1.0, norm)[:, None])
    # y = z × x in world space; in local coordinates the cross product carries the frame's
    # handedness (s × t = n for Mitsuba's frames: +1).
    hand = np.sign((np.cross(s, t) * n).sum(1))
    hand = np.where(hand == 0.0, 1.0, hand)
    y = np.cross(z, x) * hand[:, None]
    return x, y, z


def _to_table(w, axes):
    x, y, z = axes
    return np.stack([(w * x).sum(1), (w * y).sum(1), (w * z).sum(1)], 1)


def _from_table(w, axes):
    x, y, z = axes
    return w[:, :1] * x + w[:, 1:2] * y + w[:, 2:3] * z


def _valid(w):
    return np.isfinite(w).all(1) & ((w * w).sum(1) > 1e-20)


def _safe(w, ok):
    return np.where(ok[:, None], w, np.array([0.0, 0.0, 1.0]))


_classes = {}


def enable_jit_evaluation():
    """Dr.Jit flags the JIT variants need for this plugin (evaluated loops and calls)."""
    import drjit as dr

    dr.set_flag(dr.JitFlag.SymbolicLoops, False)
    dr.set_flag(dr.JitFlag.SymbolicCalls, False)


def _make_class(mi):
    import drjit as dr

    scalar = mi.variant().startswith("scalar")
    flags_all = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.GlossyTransmission | \
        mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide | mi.BSDFFlags.NonSymmetric

    def arr3(v):
        """A Mitsuba 3-vector (scalar or JIT) as numpy [n, 3] float64."""
        a = np.array(v, dtype=np.float64)
        return a.reshape(1, 3) if a.ndim == 1 else np.ascontiguousarray(a.T)

    def arr1(v):
        return np.atleast_1d(np.array(v, dtype=np.float64))

    def vec3(a):
        return mi.Vector3f(*(float(x) for x in a[0])) if scalar else mi.Vector3f(a.T.astype(np.float32))

    def spectrum(f):
        if scalar:
            return mi.Spectrum(*(float(x) for x in f[0]))
        return mi.Spectrum(np.ascontiguousarray(f.T, dtype=np.float32))

    def floats(p):
        return mi.Float(float(p[0])) if scalar else mi.Float(p.astype(np.float32))

    class BakerBcsdf(mi.BSDF):
        """`baker_bcsdf`: a `.bcsdf` table on a fiber curve (see baker_formats.mitsuba)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            section = props["section"] if props.has_property("section") else None
            if not props.has_property("filename"):
                raise ValueError(f"{PLUGIN}: the parameter 'filename' is required")
            self.path = resolve_path(str(props["filename"]), section)
            self.table = BcsdfTable(self.path)
            v = props["variant"] if props.has_property("variant") else 0
            self.variant = resolve_variant(self.table, v)
            self.variant_name = self.table.variants[self.variant]
            channels = self.table.channels
            if channels == ["R", "G", "B"]:
                self._expand = lambda f: f
            elif len(channels) == 1:
                self._expand = lambda f: np.repeat(f, 3, axis=1)
            else:
                raise ValueError(f"{PLUGIN}: {self.path} has channels {channels}; the plugin needs "
                                 "R, G, B (bake with 'channels: rgb') or a single channel")
            up = np.array(props["up"], dtype=np.float64).reshape(3) if props.has_property("up") \
                else np.array([0.0, 0.0, 1.0])
            if not np.isfinite(up).all() or not (up * up).sum() > 0:
                raise ValueError(f"{PLUGIN}: 'up' = {up.tolist()} is not a direction")
            self.up = up / np.sqrt((up * up).sum())
            self._warned = False
            self.m_flags = flags_all
            self.m_components = [flags_all]

        # -- helpers --

        def _axes(self, si, m):
            fr = si.sh_frame
            s, t, n = arr3(fr.s), arr3(fr.t), arr3(fr.n)
            if len(s) != m:
                s, t, n = (np.broadcast_to(a, (m, 3)) for a in (s, t, n))
            if not self._warned:
                # bsplinecurve sets dp_dv along the fiber and t = dp_dv/|dp_dv|; linearcurve
                # (Mitsuba 3.9.1) leaves dp_du = dp_dv = 0 and t arbitrary about n.
                dv = arr3(si.dp_dv)
                no_tangent = ((n * n).sum(1) > 0.25) & ((dv * dv).sum(1) == 0.0)
                if no_tangent.any():
                    self._warned = True
                    warnings.warn(f"{PLUGIN}: hit a shape without a fiber tangent (dp_dv = 0, e.g. "
                                  "linearcurve in Mitsuba 3.9): its shading frame's t is not the fiber "
                                  "axis; use bsplinecurve", RuntimeWarning, stacklevel=2)
            return _local_axes(s, t, n, self.up)

        def _enabled(self, ctx):
            return ctx.is_enabled(mi.BSDFFlags.GlossyReflection) or \
                ctx.is_enabled(mi.BSDFFlags.GlossyTransmission)

        def _lanes(self, si, wo, active):
            wi_l = arr3(si.wi)
            wo_l = arr3(wo)
            m = max(len(wi_l), len(wo_l))
            wi_l, wo_l = np.broadcast_to(wi_l, (m, 3)), np.broadcast_to(wo_l, (m, 3))
            act = np.broadcast_to(arr1(active).astype(bool), (m,))
            axes = self._axes(si, m)
            ok = act & _valid(wi_l) & _valid(wo_l)
            return _safe(_to_table(wi_l, axes), ok), _safe(_to_table(wo_l, axes), ok), ok

        def _eval_pdf_np(self, si, wo, active):
            wi_t, wo_t, ok = self._lanes(si, wo, active)
            f, p = self.table.eval_pdf_many(wi_t, wo_t, self.variant)
            f = self._expand(f.astype(np.float64)) * ok[:, None]
            return f, p * ok

        # -- the BSDF interface --

        def eval(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return dr.zeros(mi.Spectrum) if scalar else dr.zeros(mi.Spectrum, dr.width(wo))
            return spectrum(self._eval_pdf_np(si, wo, active)[0])

        def pdf(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                return mi.Float(0.0) if scalar else dr.zeros(mi.Float, dr.width(wo))
            return floats(self._eval_pdf_np(si, wo, active)[1])

        def eval_pdf(self, ctx, si, wo, active=True):
            if not self._enabled(ctx):
                z = dr.zeros(mi.Float, 1 if scalar else dr.width(wo))
                return (dr.zeros(mi.Spectrum) if scalar else dr.zeros(mi.Spectrum, dr.width(wo))), z
            f, p = self._eval_pdf_np(si, wo, active)
            return spectrum(f), floats(p)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi_l = arr3(si.wi)
            u = np.array(sample2, dtype=np.float64)
            u = u.reshape(1, 2) if u.ndim == 1 else np.ascontiguousarray(u.T)
            m = max(len(wi_l), len(u))
            wi_l, u = np.broadcast_to(wi_l, (m, 3)), np.broadcast_to(np.clip(u, 0.0, 1.0), (m, 2))
            act = np.broadcast_to(arr1(active).astype(bool), (m,)) & _valid(wi_l)
            if not self._enabled(ctx):
                act = act & False
            axes = self._axes(si, m)
            wi_t = _safe(_to_table(wi_l, axes), act)
            wo_t, p, f = self.table.sample_many(wi_t, u, self.variant)
            ok = act & (p > 0.0)
            wo_l = _from_table(wo_t, axes)
            wo_l = np.where(ok[:, None], wo_l, 0.0)
            weight = self._expand(f.astype(np.float64)) / np.where(ok, p, 1.0)[:, None] * ok[:, None]
            refl = (wo_l[:, 2] * wi_l[:, 2]) >= 0.0
            bs = dr.zeros(mi.BSDFSample3f) if scalar else dr.zeros(mi.BSDFSample3f, m)
            bs.wo = vec3(wo_l)
            bs.pdf = floats(np.where(ok, p, 0.0))
            bs.eta = 1.0
            bs.sampled_component = 0
            if scalar:
                bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.GlossyReflection if refl[0]
                                                else mi.BSDFFlags.GlossyTransmission))
            else:
                bs.sampled_type = mi.UInt32(np.where(
                    refl, int(mi.BSDFFlags.GlossyReflection),
                    int(mi.BSDFFlags.GlossyTransmission)).astype(np.uint32))
            return bs, spectrum(weight)

        def traverse(self, callback):
            pass

        def to_string(self):
            return (f"BakerBcsdf[filename={self.path!r}, variant={self.variant} "
                    f"({self.variant_name!r}), up={self.up.tolist()}]")

    if not scalar:
        return BakerBcsdf

    refl_type = mi.UInt32(int(mi.BSDFFlags.GlossyReflection))
    trans_type = mi.UInt32(int(mi.BSDFFlags.GlossyTransmission))

    class BakerBcsdfScalar(BakerBcsdf):
        """The scalar variants: the same frame and calls as the batched path, in plain Python
        floats (one native call per query, no numpy)."""

        def _frame(self, si):
            """(a, c, hand): the table's x axis is (a, 0, c) in local coordinates, its y axis
            hand·(c, 0, −a) (= z × x, the tangent z local y); see `_local_axes`."""
            fr = si.sh_frame
            s, t, n = fr.s, fr.t, fr.n
            up = self.up
            if n[0] * n[0] + n[1] * n[1] + n[2] * n[2] < 0.25:
                a, c, hand = up[0], up[2], 1.0
            else:
                if not self._warned:
                    dv = si.dp_dv
                    if dv[0] == 0.0 and dv[1] == 0.0 and dv[2] == 0.0:
                        self._axes(si, 1)              # warns
                a = s[0] * up[0] + s[1] * up[1] + s[2] * up[2]
                c = n[0] * up[0] + n[1] * up[1] + n[2] * up[2]
                cx = s[1] * t[2] - s[2] * t[1]
                cy = s[2] * t[0] - s[0] * t[2]
                cz = s[0] * t[1] - s[1] * t[0]
                hand = -1.0 if cx * n[0] + cy * n[1] + cz * n[2] < 0.0 else 1.0
            r = (a * a + c * c) ** 0.5
            if r < 1e-3:
                return 0.0, 1.0, hand
            return a / r, c / r, hand

        @staticmethod
        def _to(w, fr):
            a, c, hand = fr
            return [a * w[0] + c * w[2], hand * (c * w[0] - a * w[2]), w[1]]

        @staticmethod
        def _from(w, fr):
            a, c, hand = fr
            return mi.Vector3f(a * w[0] + hand * c * w[1], w[2], c * w[0] - hand * a * w[1])

        @staticmethod
        def _ok(w):
            x, y, z = float(w[0]), float(w[1]), float(w[2])
            return math.isfinite(x + y + z) and x * x + y * y + z * z > 1e-20

        def _color(self, f):
            return mi.Spectrum(f[0], f[1], f[2]) if len(f) == 3 else mi.Spectrum(f[0], f[0], f[0])

        def eval(self, ctx, si, wo, active=True):
            if not (active and self._enabled(ctx) and self._ok(si.wi) and self._ok(wo)):
                return mi.Spectrum(0.0)
            fr = self._frame(si)
            return self._color(self.table._t.eval(self._to(si.wi, fr), self._to(wo, fr), self.variant))

        def pdf(self, ctx, si, wo, active=True):
            if not (active and self._enabled(ctx) and self._ok(si.wi) and self._ok(wo)):
                return mi.Float(0.0)
            fr = self._frame(si)
            return mi.Float(self.table._t.pdf(self._to(si.wi, fr), self._to(wo, fr), self.variant))

        def eval_pdf(self, ctx, si, wo, active=True):
            if not (active and self._enabled(ctx) and self._ok(si.wi) and self._ok(wo)):
                return mi.Spectrum(0.0), mi.Float(0.0)
            fr = self._frame(si)
            a, b = self._to(si.wi, fr), self._to(wo, fr)
            t = self.table._t
            return self._color(t.eval(a, b, self.variant)), mi.Float(t.pdf(a, b, self.variant))

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            if not (active and self._enabled(ctx) and self._ok(si.wi)):
                return bs, mi.Spectrum(0.0)
            fr = self._frame(si)
            wi = self._to(si.wi, fr)
            u1 = min(max(float(sample2[0]), 0.0), 1.0)
            u2 = min(max(float(sample2[1]), 0.0), 1.0)
            t = self.table._t
            got = t.sample(wi, u1, u2, self.variant)
            if got is None or not got[1] > 0.0:
                return bs, mi.Spectrum(0.0)
            wo_t, p = got
            f = t.eval(wi, list(wo_t), self.variant)
            bs.wo = self._from(wo_t, fr)
            bs.pdf = p
            bs.eta = 1.0
            bs.sampled_component = 0
            bs.sampled_type = refl_type if bs.wo[2] * si.wi[2] >= 0.0 else trans_type
            return bs, self._color([x / p for x in f])

    return BakerBcsdfScalar


def plugin_class():
    """The plugin's class for the current Mitsuba variant."""
    import mitsuba as mi

    if mi.variant() is None:
        raise RuntimeError(f"{PLUGIN}: call mitsuba.set_variant(...) before register()")
    if mi.variant() not in _classes:
        _classes[mi.variant()] = _make_class(mi)
    return _classes[mi.variant()]


def register():
    """Registers `baker_bcsdf` with Mitsuba for the current variant (call after set_variant)."""
    import mitsuba as mi

    cls = plugin_class()
    mi.register_bsdf(PLUGIN, lambda props: cls(props))
    return cls


__all__ = ["PLUGIN", "register", "plugin_class", "resolve_path", "resolve_variant",
           "enable_jit_evaluation"]
