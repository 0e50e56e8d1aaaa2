#!/usr/bin/env python3
"""Cross-check of `baker mc` (Monte Carlo) total reflectance and transmittance against adding-doubling.

How to run (from anywhere; the repository root is found from this file's path):

    pip install -r validation/requirements.txt
    python3 validation/check_adding_doubling.py                             # builds the release binary
    python3 validation/check_adding_doubling.py --baker target/release/baker  # skip cargo
    python3 validation/check_adding_doubling.py --only 'n=1.4' -v          # subset, with breakdown

Reference: the adding-doubling (AD) solution of the radiative transport equation,
S. A. Prahl, M. J. C. van Gemert, A. J. Welch, "Determining the optical properties of turbid
media by using the adding-doubling method", Appl. Opt. 32(4), 559-568 (1993), as implemented
in Prahl's Python package `iadpython` (version 0.5.3, pinned in validation/requirements.txt).
Nothing of the Rust code is reused.

Geometry: one homogeneous slab of index n between air (n_above = n_below = 1), physical
thickness 1 mm, optical thickness b = mu_t * d, albedo a = mu_s / mu_t, Henyey-Greenstein
anisotropy g; pencil beam at normal incidence (AD: collimated normal illumination; total
fluxes do not depend on the beam's width). Semi-infinite cases use d = "inf" in the stack
(mu_t = 1/mm) and b = 1e4 in AD (its transmission underflows to 0).

What is compared (per case, both must pass):
  * R_total: AD `UR1` vs MC `rsp + rd + rd_unscattered`. UR1 is the total reflectance for
    collimated normal incidence and *includes* the specular reflection at the top surface and
    the unscattered light that comes back out of the top after reflecting inside the slab
    (the script checks this at start-up: for a = 0, UR1 equals iadpython's
    `unscattered_rt()` reflectance, which is the specular/unscattered term).
  * T_total: AD `UT1` vs MC `tt`. Both include the unscattered (ballistic) transmission.
  Standard error: R's SE is sqrt(rsp_se^2 + rd_se^2 + rd_unscattered_se^2) (missing *_se
  keys count as 0; this ignores the components' negative covariance, i.e. is conservative);
  T's SE is tt_se.
  Pass: |MC - AD| <= 4*SE_MC + 2e-4 (2e-4 allows for the AD discretisation).
  Seeds are fixed per case (CRC32 of the case name), so runs are reproducible for a given
  binary and thread count.

AD accuracy: 24 quadrature points when n = 1, 48 (24 Gauss below the critical angle + 24
Radau above) when n != 1. iadpython 0.5.3 computes Radau weights from a numpy poly1d
derivative that loses precision above ~24 points (weights off by 4e-5 at 32 points, garbage
at 64), so more points would be *less* accurate; the script refuses to run if the Radau
weights it will use do not sum to 1 within 1e-6. Convergence, estimated as the change from
16 (n = 1) or 32 (n != 1) points, is <= ~3e-5 for every case here; it is printed ("AD conv")
and a warning is given if it exceeds 1e-4. Sanity anchor: a = 0.9, g = 0.75, b = 2, n = 1
gives UR1 = 0.09739, UT1 = 0.66096 (van de Hulst's tabulated values).

Case grid: slabs with a in {0.5, 0.9, 0.99} x g in {0, 0.75, 0.9} x n in {1.0, 1.4} x
b in {1, 4} (36 cases, --photons each, default 2e6), plus semi-infinite a in {0.9, 0.99} x
g in {0, 0.9}, n = 1.4 (4 cases, --photons-semi each, default 1e6).

Multilayer stacks (6 cases, `ml:` names, listed with their layers before the table): several
scattering layers of different a, b, g (all of one index n: iadpython's quadrature is that of
one medium, so it cannot put an index step *between* scattering layers), optionally between
glass slides of other indices, clear or absorbing (in the baker: layers with mus = 0 and
mua = b_slide / d_slide), in air. AD: each layer's R/T matrices by iadpython's doubling
(`combine.simple_single_layer_matrices`), layers joined top to bottom by `combine.add_layers`
(the asymmetric form: R and T from above and from below are kept apart), then the slides by
`combine.add_slide_above` / `add_slide_below` with `start.boundary_layer`, as
`Sample.rt_matrices` does for one layer (iadpython 0.5.3's own multi-layer path,
`simple_layer_matrices` with array a/b/g, returns the reflection seen from *below* and then
treats the stack as symmetric, so it is not used). The start-up self-check pins this assembly
down: one layer reproduces `Sample.rt()` (slides equal, different, absorbing); a layer cut in
two gives the whole; a clear absorber above a scatterer hides it (UR1 <= exp(-2b) UR1) and one
below does not change UR1; with a = 0 everywhere UR1/UT1 equal the closed form for the
unscattered light through the stack (iadpython's `unscattered_rt()` ignores absorbing slides,
so it is not used there); with a = 1 and a slide of lower index than the slab, UR1 + UT1 = 1.
The semi-infinite bottom layer of `ml:layer on semi-inf` uses b = 1e4 in AD.

A fix to iadpython 0.5.3: `absorbing_glass_RT` (the slide's R, T per quadrature angle) returns
R = 2 for angles beyond the slab-to-slide critical angle when the slide's index is *below* the
slab's (there r1 = r2 = 1, and its 0/0 guard yields 1 for the second term of r1 + ...), so
R + T = 1.16 for a non-absorbing stack and UR1 jumps by 1e-2 with the number of quadrature
points. The script wraps it to give R = 1, T = 0 there (total internal reflection), only if the
bug is present (`patch_iadpython`); `ml:abs.glass|slab|1.33` needs it.

With these defaults the MC SEs are ~2e-5..4e-4, and the MC runs take ~55 s in all on 2 cores
(release build); the script prints its total runtime.

Global test (over all cases; the per-case 4-sigma checks cannot see a bias shared by all
cases, e.g. every z near +2): the mean of all z-scores and their rms must lie within bounds
derived from the number of z-scores at a family-wise false-alarm rate of 1e-3; see
`global_z_test` for the statistics, including the R-T correlation within one run.

Prints a table (case, AD, MC +- SE, z-score for R and T), then the global test, the runtime and
finally `check_adding_doubling: N passed, M failed` (N, M count (case, quantity) comparisons,
two per case, plus the two global tests); exits with 1 if any comparison fails or the baker
cannot be run.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.stats
import iadpython
import iadpython.combine
import iadpython.quadrature
import iadpython.start

REPO = Path(__file__).resolve().parent.parent

TOL_AD = 2e-4  # allowance for the adding-doubling discretisation
K_SIGMA = 4.0  # allowed number of MC standard errors
B_SEMI_INFINITE = 1e4  # AD optical thickness standing in for a semi-infinite medium
MUT_SEMI_INFINITE = 1.0  # mu_t [1/mm] of the semi-infinite MC stacks
GRID = {"dr_mm": 0.01, "nr": 100}
ALPHA_GLOBAL = 1e-3  # family-wise false-alarm rate of the global mean/rms test


@dataclass
class Case:
    a: float
    g: float
    n: float
    b: float  # optical thickness; math.inf for semi-infinite
    photons: int

    @property
    def semi_infinite(self) -> bool:
        return math.isinf(self.b)

    @property
    def name(self) -> str:
        b = "inf" if self.semi_infinite else f"{self.b:g}"
        return f"a={self.a:g} g={self.g:g} n={self.n:g} b={b}"

    @property
    def seed(self) -> int:
        return zlib.crc32(self.name.encode()) & 0x7FFFFFFF

    def stack(self) -> dict:
        if self.semi_infinite:
            d, mut = "inf", MUT_SEMI_INFINITE
        else:
            d, mut = 1.0, self.b / 1.0
        layer = {
            "name": "slab",
            "d_mm": d,
            "eta": self.n,
            "mua_per_mm": (1.0 - self.a) * mut,
            "mus_per_mm": self.a * mut,
            "g": self.g,
        }
        return {"n_above": 1.0, "n_below": 1.0, "layers": [layer], "grid": GRID}


@dataclass
class Layer:
    """A scattering (or, with a = 0, purely absorbing) layer of a multilayer stack."""
    a: float
    b: float  # optical thickness; math.inf for a semi-infinite last layer
    g: float
    d_mm: float  # physical thickness in the MC stack (math.inf with b = inf)


@dataclass
class Slide:
    """A glass slide: no scattering, index n, absorption optical thickness b (normal to it)."""
    n: float
    b: float = 0.0
    d_mm: float = 0.5  # only matters to the MC through mua = b / d


@dataclass
class StackCase:
    """Several layers of one index n, optionally between slides, in air."""
    label: str
    n: float
    layers: list[Layer]
    above: Slide | None
    below: Slide | None
    photons: int

    @property
    def semi_infinite(self) -> bool:
        return math.isinf(self.layers[-1].b)

    @property
    def name(self) -> str:
        return "ml:" + self.label

    @property
    def seed(self) -> int:
        return zlib.crc32(self.name.encode()) & 0x7FFFFFFF

    def describe(self) -> str:
        def slide(s: Slide | None) -> str:
            if s is None:
                return "air"
            return f"glass n={s.n:g}" + (f" b={s.b:g}" if s.b else " clear")
        parts = [slide(self.above)]
        parts += [f"[a={l.a:g} g={l.g:g} b={'inf' if math.isinf(l.b) else f'{l.b:g}'} n={self.n:g}]"
                  for l in self.layers]
        parts.append(slide(self.below))
        return " | ".join(parts)

    def stack(self) -> dict:
        def slide_layer(s: Slide, name: str) -> dict:
            return {"name": name, "d_mm": s.d_mm, "eta": s.n, "mua_per_mm": s.b / s.d_mm,
                    "mus_per_mm": 0.0, "g": 0.0}
        layers = []
        if self.above is not None:
            layers.append(slide_layer(self.above, "slide above"))
        for i, l in enumerate(self.layers):
            if math.isinf(l.b):
                d, mut = "inf", MUT_SEMI_INFINITE
            else:
                d, mut = l.d_mm, l.b / l.d_mm
            layers.append({"name": f"layer {i}", "d_mm": d, "eta": self.n,
                           "mua_per_mm": (1.0 - l.a) * mut, "mus_per_mm": l.a * mut, "g": l.g})
        if self.below is not None:
            layers.append(slide_layer(self.below, "slide below"))
        return {"n_above": 1.0, "n_below": 1.0, "layers": layers, "grid": GRID}


def cases(photons: int, photons_semi: int) -> list[Case | StackCase]:
    out: list[Case | StackCase] = []
    for n in (1.0, 1.4):
        for b in (1.0, 4.0):
            for a in (0.5, 0.9, 0.99):
                for g in (0.0, 0.75, 0.9):
                    out.append(Case(a, g, n, b, photons))
    for a in (0.9, 0.99):
        for g in (0.0, 0.9):
            out.append(Case(a, g, 1.4, math.inf, photons_semi))
    out += [
        # a slab between identical clear slides of higher index
        StackCase("glass|slab|glass", 1.4, [Layer(0.9, 2.0, 0.75, 1.0)],
                  Slide(1.5), Slide(1.5), photons),
        # two different scattering layers, one index, in air
        StackCase("2 layers n=1.4", 1.4, [Layer(0.95, 2.0, 0.9, 0.5), Layer(0.7, 3.0, 0.0, 1.0)],
                  None, None, photons),
        # three layers between different slides (indices 1.5 | 1.33 | 1.7)
        StackCase("1.5|3 layers n=1.33|1.7", 1.33,
                  [Layer(0.5, 0.5, 0.0, 0.2), Layer(0.99, 3.0, 0.8, 1.0), Layer(0.9, 1.0, 0.5, 0.5)],
                  Slide(1.5), Slide(1.7), photons),
        # an absorbing slide above, a clear slide of *lower* index than the slab below
        StackCase("abs.glass|slab|1.33", 1.4, [Layer(0.99, 4.0, 0.9, 1.0)],
                  Slide(1.5, b=0.3, d_mm=1.0), Slide(1.33), photons),
        # index-matched (n = 1 throughout), a clear absorbing layer between two scatterers
        StackCase("3 layers n=1, clear mid", 1.0,
                  [Layer(0.9, 1.0, 0.9, 0.5), Layer(0.0, 0.5, 0.0, 0.25), Layer(0.95, 2.0, 0.0, 1.0)],
                  None, None, photons),
        # a thin forward-scattering layer on a semi-infinite isotropic one
        StackCase("layer on semi-inf", 1.4, [Layer(0.9, 1.0, 0.9, 0.2), Layer(0.99, math.inf, 0.0, math.inf)],
                  None, None, photons_semi),
    ]
    return out


# ---------------------------------------------------------------- adding-doubling (iadpython)

def quad_points(n: float) -> tuple[int, int]:
    """(quadrature points used, fewer points for the convergence estimate)."""
    return (24, 16) if n == 1.0 else (48, 32)


def check_radau(npts: int) -> None:
    """iadpython's Radau weights degrade above ~24 points; refuse to use bad ones."""
    _, w = iadpython.quadrature.radau(npts, a=0, b=1)
    if abs(w.sum() - 1.0) > 1e-6:
        raise RuntimeError(f"iadpython Radau quadrature with {npts} points is inaccurate "
                           f"(weights sum to {w.sum():.12f}); use fewer quadrature points")


def ad_sample(a: float, g: float, n: float, b: float, quad: int) -> iadpython.Sample:
    bb = B_SEMI_INFINITE if math.isinf(b) else b
    return iadpython.Sample(a=a, b=bb, g=g, d=1.0, n=n, n_above=1.0, n_below=1.0, quad_pts=quad)


def patch_iadpython() -> bool:
    """Fix iadpython 0.5.3's absorbing_glass_RT under total internal reflection (see the docstring).

    Returns whether the patch was needed (and applied)."""
    orig = iadpython.fresnel.absorbing_glass_RT
    nu_tir = np.array([0.1, 0.9])  # 0.1: beyond the 1.4 -> 1.33 critical angle (cos 0.31)
    r, _ = orig(1.4, 1.33, 1.0, nu_tir, 0.0)
    if np.all(np.asarray(r) <= 1.0 + 1e-12):
        return False

    def absorbing_glass_rt_fixed(n_i, n_g, n_t, nu_i, b):
        r, t = orig(n_i, n_g, n_t, nu_i, b)
        tir = np.asarray(iadpython.fresnel.fresnel_reflection(n_i, nu_i, n_g)) >= 1.0
        if np.isscalar(r):
            return (1.0, 0.0) if bool(tir) else (r, t)
        return np.where(tir, 1.0, r), np.where(tir, 0.0, t)

    # iadpython.start looks it up as `iadpython.absorbing_glass_RT` at each call
    iadpython.absorbing_glass_RT = absorbing_glass_rt_fixed
    iadpython.fresnel.absorbing_glass_RT = absorbing_glass_rt_fixed
    return True


def ad_stack_rt(layers: list[tuple[float, float, float]], n: float, quad: int,
                above: Slide | None = None, below: Slide | None = None) -> tuple[float, float]:
    """UR1, UT1 of layers (a, b, g), top to bottom, all of index n, between optional slides, in air.

    Each layer by doubling; layers joined with the asymmetric adding equations (R, T seen from
    above and from below kept apart); then the slides, exactly as `Sample.rt_matrices` does
    for one layer with different slides.
    """
    above = above or Slide(1.0)
    below = below or Slide(1.0)
    s = iadpython.Sample(a=0.0, b=1.0, g=0.0, d=1.0, n=n, n_above=above.n, n_below=below.n,
                         quad_pts=quad)  # the layers' a, b, g are set on copies below
    s.b_above, s.b_below = above.b, below.b
    s.update_quadrature()
    R = None
    for a, b, g in layers:
        t = copy.deepcopy(s)
        t.a, t.b, t.g = a, (B_SEMI_INFINITE if math.isinf(b) else b), g
        Ri, Ti = iadpython.combine.simple_single_layer_matrices(t)
        if R is None:  # R, Rb: reflection from above / below; T, Tb: transmission down / up
            R, Rb, T, Tb = Ri, Ri, Ti, Ti
        else:
            R, Rb, T, Tb = iadpython.combine.add_layers(s, R, Rb, T, Tb, Ri, Ri, Ti, Ti)
    if not (n == 1 and above.n == 1 and below.n == 1 and above.b == 0 and below.b == 0):
        R01, R10, T01, T10 = iadpython.start.boundary_layer(s, top=True)
        R23, R32, T23, T32 = iadpython.start.boundary_layer(s, top=False)
        R02, R20, T02, T20 = iadpython.combine.add_slide_above(s, R01, R10, T01, T10, R, Rb, T, Tb)
        R, _, T, _ = iadpython.combine.add_slide_below(s, R02, R20, T02, T20, R23, R32, T23, T32)
    ur1, ut1, _, _ = s.UX1_and_UXU(R, T)
    return float(ur1), float(ut1)


def ad_rt(case: Case | StackCase) -> dict:
    """AD total reflectance/transmittance (collimated normal incidence) and a convergence estimate."""
    q, q_low = quad_points(case.n)
    check_radau(q if case.n == 1.0 else q // 2)
    if isinstance(case, StackCase):
        layers = [(l.a, l.b, l.g) for l in case.layers]
        ur1, ut1 = ad_stack_rt(layers, case.n, q, case.above, case.below)
        ur1_l, ut1_l = ad_stack_rt(layers, case.n, q_low, case.above, case.below)
        r_u = t_u = math.nan  # not computed for stacks (verbose output only)
    else:
        ur1, ut1, _, _ = ad_sample(case.a, case.g, case.n, case.b, q).rt()
        ur1_l, ut1_l, _, _ = ad_sample(case.a, case.g, case.n, case.b, q_low).rt()
        r_u, t_u = ad_sample(case.a, case.g, case.n, case.b, q).unscattered_rt()
    return {
        "R": float(ur1),
        "T": float(ut1),
        "R_unscattered": float(r_u),
        "T_unscattered": float(t_u),
        "conv": float(max(abs(ur1 - ur1_l), abs(ut1 - ut1_l))),
        "quad_pts": q,
    }


def unscattered_stack_exact(n: float, b: float, above: Slide, below: Slide) -> tuple[float, float]:
    """Closed-form R, T at normal incidence of air | slide | clear absorbing slab | slide | air."""
    def fres(n1: float, n2: float) -> float:
        return ((n1 - n2) / (n1 + n2)) ** 2

    def slab(r1: float, r2: float, x: float) -> tuple[float, float]:
        # incoherent multiple reflections; r1 on the entry side, x = exp(-b) one way
        den = 1 - r1 * r2 * x * x
        return r1 + (1 - r1) ** 2 * r2 * x * x / den, (1 - r1) * (1 - r2) * x / den

    r_top_in, t_top = slab(fres(1.0, above.n), fres(above.n, n), math.exp(-above.b))
    r_top_back, _ = slab(fres(n, above.n), fres(above.n, 1.0), math.exp(-above.b))
    r_bot, t_bot = slab(fres(n, below.n), fres(below.n, 1.0), math.exp(-below.b))
    x2 = math.exp(-2 * b)
    den = 1 - r_top_back * r_bot * x2
    return r_top_in + t_top ** 2 * r_bot * x2 / den, t_top * t_bot * math.exp(-b) / den


def ad_selfcheck() -> None:
    """Pin down iadpython's conventions that the comparison relies on."""
    # UR1/UT1 include the specular reflection and the unscattered transmission:
    # with no scattering they equal the unscattered (Fresnel + Beer) terms.
    for n in (1.0, 1.4):
        s = ad_sample(0.0, 0.0, n, 1.0, quad_points(n)[0])
        ur1, ut1, _, _ = s.rt()
        r_u, t_u = s.unscattered_rt()
        rs = ((n - 1) / (n + 1)) ** 2
        tb = math.exp(-1.0)
        r_exact = rs + (1 - rs) ** 2 * rs * tb**2 / (1 - rs**2 * tb**2)
        t_exact = (1 - rs) ** 2 * tb / (1 - rs**2 * tb**2)
        for what, got, want in (("UR1", ur1, r_u), ("UT1", ut1, t_u),
                                ("unscattered r", r_u, r_exact), ("unscattered t", t_u, t_exact)):
            if abs(float(got) - float(want)) > 1e-5:
                raise RuntimeError(f"iadpython convention check failed (n={n}, a=0): "
                                   f"{what} = {float(got):.6f}, expected {float(want):.6f}")
    # Anchor: van de Hulst's tabulated slab (a=0.9, g=0.75, b=2, n=1): R=0.09739, T=0.66096.
    ur1, ut1, _, _ = ad_sample(0.9, 0.75, 1.0, 2.0, 24).rt()
    if abs(ur1 - 0.09739) > 5e-5 or abs(ut1 - 0.66096) > 5e-5:
        raise RuntimeError(f"iadpython anchor check failed: R={ur1:.5f} T={ut1:.5f}, "
                           "expected 0.09739 / 0.66096")
    stack_selfcheck()


def stack_selfcheck() -> None:
    """Pin down the multilayer assembly `ad_stack_rt` (see the module docstring)."""
    def close(what: str, got: tuple[float, float], want: tuple[float, float], tol: float) -> None:
        if max(abs(got[0] - want[0]), abs(got[1] - want[1])) > tol:
            raise RuntimeError(f"multilayer AD self-check failed ({what}): UR1, UT1 = "
                               f"{got[0]:.7f}, {got[1]:.7f}, expected {want[0]:.7f}, {want[1]:.7f}")

    for n, above, below in ((1.0, Slide(1.0), Slide(1.0)), (1.4, Slide(1.0), Slide(1.0)),
                            (1.4, Slide(1.5), Slide(1.5)), (1.33, Slide(1.5), Slide(1.7)),
                            (1.4, Slide(1.5, b=0.3), Slide(1.33, b=0.1))):
        q = quad_points(n)[0]
        s = iadpython.Sample(a=0.8, b=1.5, g=0.5, d=1.0, n=n, n_above=above.n, n_below=below.n,
                             quad_pts=q)
        s.b_above, s.b_below = above.b, below.b
        ur1, ut1, _, _ = s.rt()
        one = ad_stack_rt([(0.8, 1.5, 0.5)], n, q, above, below)
        close(f"one layer vs Sample.rt, n={n}, slides {above}, {below}", one, (float(ur1), float(ut1)), 1e-9)
        close(f"layer cut in two, n={n}", ad_stack_rt([(0.8, 0.6, 0.5), (0.8, 0.9, 0.5)], n, q, above, below),
              one, 1e-6)
        close(f"a = 0 vs closed form, n={n}, slides {above}, {below}",
              ad_stack_rt([(0.0, 0.4, 0.0), (0.0, 0.6, 0.0)], n, q, above, below),
              unscattered_stack_exact(n, 1.0, above, below), 1e-6)
    for above, below in ((Slide(1.5), Slide(1.33)), (Slide(1.33), Slide(1.33)), (Slide(1.33), Slide(1.7))):
        ur1, ut1 = ad_stack_rt([(1.0, 4.0, 0.9)], 1.4, quad_points(1.4)[0], above, below)
        if abs(ur1 + ut1 - 1.0) > 1e-6:
            raise RuntimeError(f"multilayer AD self-check failed: no absorption, slides {above}, "
                               f"{below}: UR1 + UT1 = {ur1 + ut1:.7f}, expected 1")
    scat = ad_stack_rt([(0.99, 4.0, 0.0)], 1.0, 24)
    top = ad_stack_rt([(0.0, 1.0, 0.0), (0.99, 4.0, 0.0)], 1.0, 24)
    bottom = ad_stack_rt([(0.99, 4.0, 0.0), (0.0, 1.0, 0.0)], 1.0, 24)
    if not top[0] <= math.exp(-2.0) * scat[0] or abs(bottom[0] - scat[0]) > 1e-9:
        raise RuntimeError(f"multilayer AD orientation check failed: UR1 scatterer {scat[0]:.6f}, "
                           f"under an absorber {top[0]:.6f} (must be <= {math.exp(-2) * scat[0]:.6f}), "
                           f"over an absorber {bottom[0]:.6f} (must be equal)")


# ---------------------------------------------------------------- Monte Carlo (baker mc)

def build_baker() -> Path:
    print("building: cargo build --release -q -p baker", flush=True)
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "baker"], cwd=REPO, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    if not target.is_absolute():
        target = REPO / target
    return target / "release" / "baker"


def run_mc(baker: Path, case: Case, workdir: Path, timeout: float) -> dict:
    path = workdir / (re.sub(r"[^A-Za-z0-9.]+", "_", case.name) + ".json")
    path.write_text(json.dumps(case.stack(), indent=1))
    cmd = [str(baker), "mc", str(path), "--photons", str(case.photons), "--seed", str(case.seed), "--json"]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"`{' '.join(cmd)}` exited {p.returncode}:\n{p.stderr.strip()}")
    try:
        doc = json.loads(p.stdout)
    except json.JSONDecodeError as e:
        raise RuntimeError(f"`{' '.join(cmd)}` did not print one JSON object ({e}):\n{p.stdout[:500]}")
    doc["_wall_s"] = wall
    return doc


def num(doc: dict, key: str) -> float:
    v = doc.get(key, 0.0)
    return 0.0 if v is None else float(v)


def mc_rt(doc: dict) -> dict:
    missing = [k for k in ("rsp", "rd", "rd_unscattered", "tt", "rd_se", "tt_se") if k not in doc]
    if missing:
        raise RuntimeError(f"baker mc JSON lacks keys {missing}")
    r_keys = ("rsp", "rd", "rd_unscattered")
    out = {
        "R": sum(num(doc, k) for k in r_keys),
        "R_se": math.sqrt(sum(num(doc, k + "_se") ** 2 for k in r_keys)),
        "T": num(doc, "tt"),
        "T_se": num(doc, "tt_se"),
    }
    # Correlation of the R and T estimates (see global_z_test): a photon leaves through the top
    # or the bottom, never both, so per photon (R weight - Rsp) * (T weight) = 0 and
    # Cov(R, T) = -(R - Rsp) * T / N (Rsp is exact, its SE 0).
    photons = num(doc, "photons")
    if photons > 1 and out["R_se"] > 0 and out["T_se"] > 0:
        rho = -(out["R"] - num(doc, "rsp")) * out["T"] / ((photons - 1) * out["R_se"] * out["T_se"])
        out["rho"] = min(0.0, max(-1.0, rho))
    else:
        out["rho"] = 0.0
    return out


# ---------------------------------------------------------------- comparison

def judge(ad: float, mc: float, se: float) -> tuple[bool, float]:
    diff = mc - ad
    ok = abs(diff) <= K_SIGMA * se + TOL_AD
    if abs(diff) < 1e-12:  # e.g. semi-infinite T: MC exactly 0, AD ~1e-244
        return ok, 0.0
    z = diff / se if se > 0 else math.copysign(math.inf, diff)
    return ok, z


def global_z_test(groups: list[tuple[list[float], float]], alpha: float = ALPHA_GLOBAL) -> list[dict]:
    """Global test of all z-scores: their mean and rms, at family-wise false-alarm rate alpha.

    groups: per case, its z-scores (one or two: R and T; a z of exactly 0, semi-infinite T,
    is left out) and rho, the correlation of its R and T estimates.

    Under the null hypothesis (MC unbiased, SEs right; AD exact: its own error, ~1e-5 at these
    quadrature orders judging by how the printed "AD conv" change shrinks, is a fraction of
    the SEs, 2e-5..4e-4) every z is N(0, 1) (>= 1e6 photons: central limit theorem) and
    different cases are independent (separate runs and seeds). R and T of one case are not:
    they come from the same photons, and since a photon leaves through the top or the bottom,
    never both, Cov(R, T) = -(R - Rsp) T / N <= 0; rho = Cov / (SE_R SE_T) (`mc_rt`) is
    -0.05 .. -0.999 here (close to -1 for a = 0.99, where R + T is nearly 1 photon by photon).
    With n z-scores:

      * mean: Var(sum z) = n + 2 sum(rho), so SE(mean z) = sqrt(n + 2 sum(rho)) / n (1/sqrt(n)
        for independent z-scores; smaller here, as rho <= 0). Pass: |mean z| <=
        Phi^-1(1 - alpha/4) SE(mean z) (two-sided, alpha/2 in all).
      * rms: for independent z-scores sum z^2 ~ chi^2_n. A pair (z_R, z_T) of correlation rho
        is (1+rho) U^2 + (1-rho) V^2 with U, V independent N(0, 1), so sum z^2 = sum_j l_j X_j,
        X_j ~ chi^2_1 independent, weights l = 1 +- rho per pair and 1 for a lone z. That is
        approximated by Satterthwaite's c chi^2_nu of the same mean and variance:
        c = sum l^2 / sum l, nu = (sum l)^2 / sum l^2 (exactly chi^2_n when every rho = 0;
        a plain chi^2_n band would be too narrow here, as strongly correlated pairs count
        for less than two independent z-scores). Checked by simulating sum l_j X_j with the
        default grid's rhos (2e6 draws): the band's tails hold 1.9e-4 and 3.3e-4 (nominal
        2.5e-4 each), while the plain chi^2_87 band's would hold 1.6e-3 and 2.0e-3. Pass: c chi^2_nu quantile(alpha/4) <= sum z^2 <=
        c chi^2_nu quantile(1 - alpha/4) (two-sided, alpha/2 in all), i.e. rms = sqrt(sum z^2 / n)
        within the square roots of those over n.
    Bonferroni: alpha/2 + alpha/2 = alpha for the two tests together. (The SE of R used for
    z_R ignores the small negative covariance of Rd and the unscattered Rd, so Var(z_R) is a
    little below 1: conservative for the mean and the upper rms bound, and below 1 % for the
    lower one.)
    """
    zs = [z for zz, _ in groups for z in zz]
    n = len(zs)
    if n == 0:
        return []
    zz = np.array(zs)
    sum_rho = sum(rho for z2, rho in groups if len(z2) == 2)
    lam = []
    for z2, rho in groups:
        lam += [1 + rho, 1 - rho] if len(z2) == 2 else [1.0] * len(z2)
    lam = np.array(lam)
    c = float((lam**2).sum() / lam.sum())
    nu = float(lam.sum() ** 2 / (lam**2).sum())

    se_mean = math.sqrt(max(n + 2 * sum_rho, 1.0)) / n
    k = float(scipy.stats.norm.ppf(1 - alpha / 4))
    mean = float(zz.mean())
    lo_ss = c * float(scipy.stats.chi2.ppf(alpha / 4, nu))
    hi_ss = c * float(scipy.stats.chi2.ppf(1 - alpha / 4, nu))
    ss = float((zz**2).sum())
    rms = math.sqrt(ss / n)
    rms_lo, rms_hi = math.sqrt(lo_ss / n), math.sqrt(hi_ss / n)
    naive = (math.sqrt(float(scipy.stats.chi2.ppf(alpha / 4, n)) / n),
             math.sqrt(float(scipy.stats.chi2.ppf(1 - alpha / 4, n)) / n))
    return [
        {"test": "mean z", "ok": abs(mean) <= k * se_mean, "value": mean, "bound": k * se_mean,
         "text": f"mean z {mean:+.3f}, |mean| <= {k:.2f} x SE {se_mean:.4f} = {k * se_mean:.3f} "
                 f"(n = {n} z-scores, sum rho = {sum_rho:+.1f}; 1/sqrt(n) would give "
                 f"{k / math.sqrt(n):.3f})"},
        {"test": "rms z", "ok": lo_ss <= ss <= hi_ss, "value": rms, "band": (rms_lo, rms_hi),
         "text": f"rms z {rms:.3f} in [{rms_lo:.3f}, {rms_hi:.3f}] (sum z^2 = {ss:.1f} in "
                 f"[{lo_ss:.1f}, {hi_ss:.1f}] = {c:.3f} x chi2_{nu:.1f} quantiles "
                 f"{alpha / 4:g}, {1 - alpha / 4:g}; chi2_{n} for independent z-scores would "
                 f"give [{naive[0]:.3f}, {naive[1]:.3f}])"},
    ]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baker", help="baker binary to use (default: cargo build --release, target/release/baker)")
    ap.add_argument("--photons", type=float, default=2e6, help="photons per slab case (default 2e6)")
    ap.add_argument("--photons-semi", type=float, default=1e6,
                    help="photons per semi-infinite case (default 1e6)")
    ap.add_argument("--only", metavar="REGEX", help="run only cases whose name matches (e.g. 'n=1.4')")
    ap.add_argument("--timeout", type=float, default=300, help="seconds allowed per MC run (default 300)")
    ap.add_argument("--keep", metavar="DIR", help="write the stack files to DIR and keep them")
    ap.add_argument("--json-out", metavar="PATH", help="write all results as JSON to PATH")
    ap.add_argument("-v", "--verbose", action="store_true",
                    help="also print the unscattered/specular breakdown and MC timings")
    args = ap.parse_args()

    all_cases = cases(int(args.photons), int(args.photons_semi))
    if args.only:
        all_cases = [c for c in all_cases if re.search(args.only, c.name)]
        if not all_cases:
            print(f"no case matches {args.only!r}", file=sys.stderr)
            return 1

    t_start = time.perf_counter()
    print(f"iadpython {getattr(iadpython, '__version__', '?')}, numpy {np.__version__}")
    if patch_iadpython():
        print("iadpython's absorbing_glass_RT gives R > 1 under total internal reflection: patched "
              "(R = 1, T = 0 there)")
    ad_selfcheck()
    t0 = time.perf_counter()
    ad = {c.name: ad_rt(c) for c in all_cases}
    print(f"adding-doubling: {len(ad)} cases in {time.perf_counter() - t0:.1f} s "
          f"(max convergence estimate {max(v['conv'] for v in ad.values()):.1e})")
    for name, v in ad.items():
        if v["conv"] > 1e-4:
            print(f"WARNING: AD not converged to 1e-4 for {name}: change {v['conv']:.1e}")
    stacks = [c for c in all_cases if isinstance(c, StackCase)]
    if stacks:
        print("multilayer stacks, top to bottom, air above and below:")
        for c in stacks:
            print(f"  {c.name:<30} {c.describe()}")

    try:
        baker = Path(args.baker).resolve() if args.baker else build_baker()
    except subprocess.CalledProcessError as e:
        print(f"cargo build failed: {e}", file=sys.stderr)
        print("check_adding_doubling: 0 passed, 1 failed")
        return 1

    tmp = None
    if args.keep:
        workdir = Path(args.keep)
        workdir.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="check_ad_")
        workdir = Path(tmp.name)

    passed = failed = 0
    groups: list[tuple[list[float], float]] = []  # per case: its z-scores, R-T correlation
    results = []
    mc_total = 0.0
    hdr = (f"{'case':<30} {'R_AD':>8} {'R_MC':>8} {'± SE':>7} {'z':>6}   "
           f"{'T_AD':>8} {'T_MC':>8} {'± SE':>7} {'z':>6}  {'AD conv':>7}  result")
    print(hdr)
    print("-" * len(hdr))
    for c in all_cases:
        a = ad[c.name]
        try:
            doc = run_mc(baker, c, workdir, args.timeout)
            m = mc_rt(doc)
        except (RuntimeError, subprocess.TimeoutExpired, OSError) as e:
            print(f"{c.name:<30} ERROR: {e}")
            failed += 2
            results.append({"case": c.name, "error": str(e)})
            continue
        mc_total += doc["_wall_s"]
        ok_r, z_r = judge(a["R"], m["R"], m["R_se"])
        ok_t, z_t = judge(a["T"], m["T"], m["T_se"])
        case_z = []
        for ok, z in ((ok_r, z_r), (ok_t, z_t)):
            passed += ok
            failed += not ok
            if math.isfinite(z) and z != 0.0:
                case_z.append(z)
        groups.append((case_z, m["rho"]))
        bad = [q for q, ok in (("R", ok_r), ("T", ok_t)) if not ok]
        verdict = "ok" if not bad else "FAIL " + ",".join(bad)
        print(f"{c.name:<30} {a['R']:8.5f} {m['R']:8.5f} {m['R_se']:7.5f} {z_r:6.2f}   "
              f"{a['T']:8.5f} {m['T']:8.5f} {m['T_se']:7.5f} {z_t:6.2f}  {a['conv']:7.1e}  {verdict}",
              flush=True)
        if args.verbose:
            print(f"{'':<30} R-T correlation {m['rho']:+.3f}; unscattered R: AD {a['R_unscattered']:.5f}, MC rsp+rd_unscattered "
                  f"{num(doc, 'rsp') + num(doc, 'rd_unscattered'):.5f} (rsp {num(doc, 'rsp'):.5f}); "
                  f"AD unscattered T {a['T_unscattered']:.5f}; MC rd {num(doc, 'rd'):.5f}; "
                  f"{c.photons} photons in {doc['_wall_s']:.2f} s "
                  f"({doc.get('photons_per_s', float('nan')):.3g}/s, {doc.get('threads', '?')} threads)")
        results.append({"case": c.name, "seed": c.seed, "photons": c.photons, "ad": a, "rho": m["rho"],
                        "mc": m, "ok_R": ok_r, "ok_T": ok_t, "z_R": z_r, "z_T": z_t,
                        "mc_raw": {k: v for k, v in doc.items() if k not in ("r_mm", "rd_r_per_mm2",
                                                                              "rd_r_per_mm2_se")}})
    if tmp is not None:
        tmp.cleanup()

    zs = [z for zz, _ in groups for z in zz]
    glob = global_z_test(groups)
    if zs:
        zz = np.array(zs)
        rhos = [rho for z2, rho in groups if len(z2) == 2]
        print(f"MC time {mc_total:.1f} s; z-scores: n={zz.size}, mean {zz.mean():+.3f}, "
              f"rms {math.sqrt(float(np.mean(zz**2))):.3f}, max |z| {np.abs(zz).max():.2f}; "
              f"R-T correlation {min(rhos, default=0):+.2f} .. {max(rhos, default=0):+.2f}")
        print(f"global test (family-wise alpha {ALPHA_GLOBAL:g}):")
        for g in glob:
            print(f"  {'ok  ' if g['ok'] else 'FAIL'} {g['text']}")
            passed += g["ok"]
            failed += not g["ok"]
    if args.json_out:
        Path(args.json_out).write_text(json.dumps({"cases": results, "global": glob}, indent=1, default=float))
    print(f"total runtime {time.perf_counter() - t_start:.1f} s")
    print(f"check_adding_doubling: {passed} passed, {failed} failed")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
