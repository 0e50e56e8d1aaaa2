#!/usr/bin/env python3
"""How far the baker's V-cavity boundary is from Mitsuba's Smith lobe, and the fixture check.

The baker's rough fiber boundary (baker/src/fiber/surface.rs, `Surface::scatter`) traces the
photon through a V-cavity: multiple facet events, no energy lost. Mitsuba's `roughdielectric`
(tests/surfaces/rough_dielectric_beckmann.csv, written by
validation/make_rough_interface_fixture.py) is a Smith single-scattering model: one facet
event, the masked energy lost. Both use the same Beckmann D(m) and Fresnel, so their lobes
agree closely but not exactly. This script measures how closely, so that a χ² test of the
Rust sampler against the fixture can be sized: at which sample count N the model difference
alone makes the test fail.

    python3 validation/check_rough_interface.py                   # the V-cavity comparison
    python3 validation/check_rough_interface.py --check-fixture   # also recompute the CSV
                                                                  # with Mitsuba (exit 1 if
                                                                  # any p differs by > 1e-6)
    python3 validation/check_rough_interface.py --samples 200000  # fewer samples per case

The V-cavity Monte Carlo below is written from surface.rs's description, in numpy, not
translated from the Rust; per event, in the local frame with the mean normal n = nf = +z
facing the photon, d = (sin θi, 0, −cos θi), indices n1 → n2 (1 → eta outside, eta → 1
inside):
  1. a visible V-cavity facet (Heitz & d'Eon 2014 §5): m with pdf D(m)(m·n) (tan²θm =
     −α² ln u1, φm = 2π u2), its mirror m' = 2(m·n)n − m, keep m' with probability
     ⟨wi·m'⟩/(⟨wi·m⟩ + ⟨wi·m'⟩), wi = −d;
  2. at the facet: unpolarised Fresnel R (baker/src/math/fresnel.rs `dielectric`, 1 under
     total internal reflection) picks reflection or refraction;
  3. a refracted ray going down (w·n < 0) leaves; a reflected ray going up leaves with
     probability G1 = min(1, 2(n·m)(n·w)/(w·m)) (V-cavity masking, Heitz 2014 Eq. 5.4);
  4. otherwise (masked reflection) it meets the other facet m' = 2(m·n)n − m and repeats 2–4
     from there (if it faces m'; a refracted ray going up, or one that does not face m', ends
     the walk);
  5. after 8 facet events, or when the walk ends in 4, the whole event is redone on the mean
     surface (smooth Fresnel at n) and counted as a fallback.
Refracted rays are not masked (as in surface.rs).

Comparison: histogram of the new directions in the fixture's 40 × 18 (z, |φ|) bins; expected
counts N·p_b/Σp (Mitsuba's lobe renormalised to its non-lost part, since the V-cavity walk
loses nothing), bins pooled in row order (iz, then iphi) until the expected count reaches 5
(as baker/src/stats/chi2.rs `chi2_test_1d`, except that a short last group joins the one
before it), p-value from χ² with (pooled bins − 1) degrees of freedom. Reported per case:
χ²/dof and p at N = 1e5, 2e5 and 2e6 (the first N samples of one stream), how many of the
20 disjoint 1e5 chunks and 10 disjoint 2e5 chunks fail p < 1e-4, the model distance
λ = Σ (Q − P)²/P over the groups pooled for N = 2e5 (Q: V-cavity group probabilities from
the 2e6 samples, minus the noise term dof/2e6; E[χ²] ≈ dof + N λ), the same for the photons
that met a single facet (so multiple-bounce paths and single-facet lobe differences can be
told apart), N_detect (the N at which dof + N λ_N reaches the p = 1e-4 threshold) and the
three bins with the largest |q − p|/σ.
"""

import argparse
import math
import pathlib
import sys
import time

import numpy as np
from scipy import stats

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import make_rough_interface_fixture as fx  # noqa: E402

MAX_CAVITY_BOUNCES = 8
P_FAIL = 1e-4


# ---------------------------------------------------------------- the V-cavity model


def g1_vcavity(w, m):
    """min(1, 2 (n·m)(n·w)/(w·m)) with n = +z; 0 if w·m ≤ 0 or w·n ≤ 0."""
    wm = np.einsum("ij,ij->i", w, m)
    wn = w[:, 2]
    ok = (wm > 0) & (wn > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.minimum(1.0, 2.0 * m[:, 2] * wn / wm)
    return np.where(ok, g, 0.0)


def mirror(m):
    """2 (m·n) n − m for n = +z."""
    return np.stack([-m[:, 0], -m[:, 1], m[:, 2]], axis=1)


def vcavity_scatter(alpha, eta, side, theta_i_deg, n, rng):
    """n events of the V-cavity model: (directions n×3, transmitted, fallback, facet events)."""
    n1, n2 = (1.0, eta) if side == "outside" else (eta, 1.0)
    t = math.radians(theta_i_deg)
    d0 = np.array([math.sin(t), 0.0, -math.cos(t)])
    wi = np.tile(-d0, (n, 1))
    # 1. a visible V-cavity normal
    u1, u2, u3 = rng.random(n), rng.random(n), rng.random(n)
    cos_t = 1.0 / np.sqrt(1.0 - alpha * alpha * np.log(u1))
    sin_t = np.sqrt(np.maximum(0.0, 1.0 - cos_t * cos_t))
    phi = 2.0 * math.pi * u2
    m = np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=1)
    m2 = mirror(m)
    a = np.maximum(np.einsum("ij,ij->i", wi, m), 0.0)
    a2 = np.maximum(np.einsum("ij,ij->i", wi, m2), 0.0)
    swap = u3 * (a + a2) < a2
    m[swap] = m2[swap]

    out = np.zeros((n, 3))
    trans = np.zeros(n, dtype=bool)
    fallback = np.zeros(n, dtype=bool)
    events = np.zeros(n, dtype=np.int64)
    act = np.arange(n)  # rays still in the cavity
    for _ in range(MAX_CAVITY_BOUNCES):
        if act.size == 0:
            break
        k = act.size
        events[act] += 1
        # 2. Fresnel at the facet
        dirs, tr = facet(-wi[act], m[act], n1, n2, rng.random(k))
        up = dirs[:, 2] > 0
        # 3. refracted and going down: leaves; reflected and going up: leaves with prob. G1
        leave = (tr & ~up) | (~tr & up & (rng.random(k) < g1_vcavity(dirs, m[act])))
        out[act[leave]] = dirs[leave]
        trans[act[leave]] = tr[leave]
        # 4. masked: the other facet of the cavity, if the ray faces it
        rest = ~leave
        nm = mirror(m[act[rest]])
        nwi = -dirs[rest]
        cont = ~tr[rest] & (np.einsum("ij,ij->i", nwi, nm) > 0)
        fallback[act[rest][~cont]] = True
        nxt = act[rest][cont]
        m[nxt] = nm[cont]
        wi[nxt] = nwi[cont]
        act = nxt
    # 5. the mean surface
    fallback[act] = True
    fb = np.flatnonzero(fallback)
    if fb.size:
        k = fb.size
        dirs, tr = facet(np.tile(d0, (k, 1)), np.tile([0.0, 0.0, 1.0], (k, 1)), n1, n2, rng.random(k))
        out[fb] = dirs
        trans[fb] = tr
    return out, trans, fallback, events


def facet(d, m, n1, n2, u):
    """Reflect or refract directions d (k×3) at facets m (k×3) facing them (d·m < 0), from
    index n1 into n2, by the unpolarised Fresnel reflectance (baker/src/math/fresnel.rs
    `dielectric`: R = 1 under total internal reflection) and uniforms u. (dir, refracted)."""
    cos_i = -np.einsum("ij,ij->i", d, m)
    e = n1 / n2
    sin_t2 = e * e * (1.0 - cos_i * cos_i)
    tir = sin_t2 >= 1.0
    cos_t = np.sqrt(np.maximum(1.0 - sin_t2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
        rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)
        r = np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))
    refl = u < r
    out = np.empty_like(d)
    out[refl] = d[refl] + 2.0 * cos_i[refl, None] * m[refl]
    t = ~refl
    v = e * d[t] + (e * cos_i[t] - cos_t[t])[:, None] * m[t]
    out[t] = v / np.linalg.norm(v, axis=1, keepdims=True)
    return out, t


# ---------------------------------------------------------------- the χ² comparison


def histogram(w):
    iz, ip = fx.bin_index(w)
    return np.bincount(iz * fx.NPHI + ip, minlength=fx.NZ * fx.NPHI).astype(float)


def pool_groups(expected):
    """Group numbers of the bins (in row order iz, iphi): consecutive bins pooled until the
    group's expected count reaches 5, as baker/src/stats/chi2.rs `chi2_test_1d` does, except
    that a short last group is merged into the one before it (chi2_test_1d keeps it apart,
    and with a last group expected ≪ 1 a single photon there gives χ² ≫ 1000)."""
    groups = np.zeros(len(expected), dtype=np.int64)
    g, acc = 0, 0.0
    for i, e in enumerate(expected):
        groups[i] = g
        acc += e
        if acc >= 5.0:
            g, acc = g + 1, 0.0
    if acc > 0.0 and g > 0:
        groups[groups == g] = g - 1
        g -= 1
    elif acc == 0.0:
        g -= 1
    return groups, g + 1


def chi2_pooled(observed, prob):
    """Pearson χ² of the observed counts against N·prob on the pooled bins: (χ², dof, p)
    with dof = groups − 1."""
    n = observed.sum()
    groups, k = pool_groups(n * prob)
    o = np.bincount(groups, weights=observed, minlength=k)
    e = np.bincount(groups, weights=n * prob, minlength=k)
    chi2 = float(((o - e) ** 2 / e).sum())
    dof = max(k, 2) - 1
    return chi2, dof, float(stats.chi2.sf(chi2, dof))


def model_distance(q, prob, n):
    """λ_N = Σ (Q − P)²/P over the groups pooled for N samples (Q, P: the V-cavity and Mitsuba
    probabilities of a group), and that pooling's dof: E[χ²] ≈ dof + N λ_N."""
    groups, k = pool_groups(n * prob)
    qq = np.bincount(groups, weights=q, minlength=k)
    pp = np.bincount(groups, weights=prob, minlength=k)
    return float(((qq - pp) ** 2 / pp).sum()), k - 1


def n_detect(q, n_q, prob):
    """The smallest N at which the expected χ², dof + N λ_N, reaches the p = P_FAIL threshold
    (λ_N from q, the V-cavity probabilities estimated from n_q samples, minus its noise term
    dof/n_q). inf if not below 1e9."""

    def fails(n):
        lam, dof = model_distance(q, prob, n)
        lam -= dof / n_q
        return dof + n * lam > stats.chi2.isf(P_FAIL, dof)

    grid = np.geomspace(1e3, 1e9, 121)
    hit = [n for n in grid if fails(n)]
    return hit[0] if hit else math.inf


def compare_case(alpha, side, th, p, n_samples, seed):
    rng = np.random.default_rng(seed)
    w, trans, fb, events = vcavity_scatter(alpha, fx.ETA, side, th, n_samples, rng)
    prob = (p / p.sum()).ravel()
    h_all = histogram(w)
    res = {"fallback": fb.mean(), "multi": (events > 1).mean(), "T": trans.mean()}
    for n in sorted({100_000, 200_000, n_samples}):
        if n > n_samples:
            continue
        res[n] = chi2_pooled(histogram(w[:n]), prob)
    # disjoint chunks
    for n in (100_000, 200_000):
        k = n_samples // n
        if k < 1:
            continue
        ps = [chi2_pooled(histogram(w[i * n : (i + 1) * n]), prob)[2] for i in range(k)]
        res[("chunks", n)] = (k, sum(q < P_FAIL for q in ps), min(ps))
    # model distance at N = 2e5 and the N at which the model difference becomes detectable
    nn = h_all.sum()
    q = h_all / nn
    lam, dof = model_distance(q, prob, 200_000)
    res["lambda"] = lam - dof / nn
    res["n_detect"] = n_detect(q, nn, prob)
    # the same for the photons that met one facet only (diagnosis: the multiple-bounce paths
    # against the difference of the single-facet lobes, V-cavity against Smith)
    h1 = histogram(w[events == 1])
    lam1, dof1 = model_distance(h1 / h1.sum(), prob, 200_000)
    res["lambda1"] = lam1 - dof1 / h1.sum()
    # largest bin-level differences (for the report)
    sd = np.sqrt(np.maximum(prob * (1 - prob), 1 / nn) / nn)
    z = (q - prob) / sd
    top = np.argsort(-np.abs(z))[:3]
    res["worst_bins"] = [(int(i // fx.NPHI), int(i % fx.NPHI), float(prob[i]), float(q[i]), float(z[i])) for i in top]
    return res


def check_fixture(mi):
    """Recompute the fixture with Mitsuba and compare with the committed CSV (1e-6 absolute)."""
    ref, ref_loss = fx.read_fixture()
    res = fx.compute_all(mi, verbose=False)
    worst = 0.0
    ok = True
    for key, r in res.items():
        k = min(ref, key=lambda kk: abs(kk[0] - key[0]) + (kk[1] != key[1]) + abs(kk[2] - key[2]))
        if abs(k[0] - key[0]) > 1e-12 or k[1] != key[1] or k[2] != key[2]:
            print(f"  case {key} missing from the fixture")
            ok = False
            continue
        d = float(np.abs(r["p"] - ref[k]).max())
        dl = abs((1 - r["p"].sum()) - ref_loss[k])
        worst = max(worst, d, dl)
        print(f"  {fx.case_line(*key, r)}\n      max |p - csv| = {d:.1e}, |loss - csv| = {dl:.1e}")
    if len(ref) != len(res):
        print(f"  the fixture has {len(ref)} cases, the script {len(res)}")
        ok = False
    ok &= worst <= 1e-6
    print(f"fixture check: max |difference| = {worst:.1e} ({'OK' if ok else 'FAIL'}, tolerance 1e-6)")
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check-fixture", action="store_true", help="recompute the CSV with Mitsuba and compare")
    ap.add_argument("--samples", type=int, default=2_000_000, help="V-cavity samples per case")
    ap.add_argument("--seed", type=int, default=2014)
    args = ap.parse_args()
    t_start = time.time()
    ok = True
    if args.check_fixture:
        t0 = time.time()
        mi = fx.load_mitsuba()
        print("Recomputing the fixture with Mitsuba:")
        ok = check_fixture(mi)
        print(f"fixture check: {time.time() - t0:.1f}s")
    ref, ref_loss = fx.read_fixture()
    print(f"\nV-cavity (surface.rs) vs Mitsuba roughdielectric, {args.samples} samples per case, seed {args.seed}:")
    print("  (chi2/dof, p) at N; chunks: failing (p < 1e-4) / count; lambda = sum (q-p)^2/p;")
    print("  N_detect: N at which the expected chi2 reaches the p = 1e-4 threshold")
    for i, (key, p) in enumerate(sorted(ref.items(), key=lambda kv: (kv[0][0], kv[0][1] == "inside", kv[0][2]))):
        a, side, th = key
        t0 = time.time()
        r = compare_case(a, side, th, p, args.samples, args.seed + i)
        cols = []
        for n in sorted({100_000, 200_000, args.samples}):
            if n in r:
                c, dof, pv = r[n]
                cols.append(f"N={n:.0e}: {c / dof:5.2f} (dof {dof}) p={pv:.1e}")
        ch = "; ".join(
            f"{r[('chunks', n)][1]}/{r[('chunks', n)][0]} chunks of {n:.0e} fail"
            for n in (100_000, 200_000)
            if ("chunks", n) in r
        )
        print(
            f"beta={math.degrees(math.atan(a)):4.1f} {side:7s} theta_i={th:4.1f}: Mitsuba loss {ref_loss[key]:.2e}; "
            f"V-cavity T={r['T']:.5f} (Mitsuba T={p[: fx.NZ // 2].sum() / p.sum():.5f}), "
            f">1 facet {r['multi']:.2e}, fallback {r['fallback']:.1e}\n    "
            + "; ".join(cols)
            + f"\n    {ch}; lambda(2e5 pooling) = {r['lambda']:.2e} "
            + f"(one-facet photons only: {r['lambda1']:.2e}), N_detect = {r['n_detect']:.2g}"
            + "\n    largest |z| bins (iz, iphi, p, q, z): "
            + ", ".join(f"({iz},{ip},{pp:.2e},{qq:.2e},{zz:+.1f})" for iz, ip, pp, qq, zz in r["worst_bins"])
            + f"  [{time.time() - t0:.1f}s]",
            flush=True,
        )
    print(f"total {time.time() - t_start:.1f}s")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
