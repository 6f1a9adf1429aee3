#!/usr/bin/env python3
"""CAM16 corresponding colours from colour-science, the independent oracle of restauro's seen
image (`spectral/tests/cam16_oracle.rs`, `spectral/tests/breneman.rs`).

    python3 -m venv /tmp/colour-venv
    /tmp/colour-venv/bin/pip install colour-science==0.4.7
    /tmp/colour-venv/bin/python make.py

Writes, next to this script:

    cam16_stones.csv       shipped stones under six lights at four luminances: the stone's XYZ
                           under the light, the light's white, and CAM16's corresponding colour
                           under D65 for the same viewing conditions
    cam16_breneman1987.csv each pair of Breneman (1987): the colour CAM16 sees under D65 of the
                           test sample (under the test white) and of the reference sample (under
                           the reference white)

Conventions (both files): CAM16 (Li et al. 2017) as colour-science 0.4.7 implements it
(colour.XYZ_to_CAM16 / colour.CAM16_to_XYZ); average surround (F = 1, c = 0.69, N_c = 1);
Y_b = 20; L_A = 0.2 x the white's luminance; the corresponding colour is the CAM16 forward
model under the light's white, then the inverse model under D65 (x, y = 0.3127, 0.3290) with
the same L_A, Y_b and surround, J, C and h kept. XYZ are relative: Y = 1 for the white.
"""

from __future__ import annotations

import csv
import os
import warnings

warnings.filterwarnings("ignore")  # colour warns that SciPy / Matplotlib are absent

import numpy as np  # noqa: E402

import colour  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
EXPECTED_VERSION = "0.4.7"
SURROUND = colour.VIEWING_CONDITIONS_CAM16["Average"]
Y_B = 20.0
L_A_FRACTION = 0.2
D65 = colour.xy_to_XYZ(np.array([0.3127, 0.3290]))
SHAPE = colour.SpectralShape(380, 780, 5)
CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE)

STONES = [
    "brick_red_smooth__eco_0097uuubrk",
    "travertine_tufa_solid__eco_ward73",
    "marble_white_solid__eco_ward95",
    "sandstone_red_potsdam_solid__eco_ward59",
    "lichen_xanthoria_orange_on_rock__usgs_Xanthoria-1",
    "granite_biotite_grey_solid__eco_ward10",
    "conglomerate_quartz_solid__eco_ward48",
    "limestone_weathered_surface__usgs_CU02-11A",
]
WHITE_CD_M2 = [2.5, 50.0, 500.0, 5000.0]


def lights():
    d = colour.SDS_ILLUMINANTS
    return {
        "D65": d["D65"].copy(),
        "D50": d["D50"].copy(),
        "A": d["A"].copy(),
        "blackbody:3000": colour.sd_blackbody(3000),
        "daylight:10000": colour.sd_CIE_illuminant_D_series(
            colour.temperature.CCT_to_xy_CIE_D(10000 * 1.4388 / 1.4380)
        ),
        "F2": d["FL2"].copy(),
    }


def reflectances():
    path = os.path.join(ROOT, "data", "spectra")
    out = {}
    for stem in STONES:
        rows = []
        for line in open(os.path.join(path, stem + ".csv")):
            if line.startswith("#") or not line.strip():
                continue
            a, b = line.strip().split(",")[:2]
            try:
                rows.append((float(a), float(b)))
            except ValueError:
                continue  # the header line
        wl = np.array([r[0] for r in rows])
        v = np.array([r[1] for r in rows])
        # As restauro reads a shipped spectrum: each 5 nm band the mean of the samples within
        # +-2.5 nm, or the linear interpolation where the data are sparser; held at the ends.
        bands = []
        for lam in SHAPE.wavelengths:
            inside = v[(wl >= lam - 2.5) & (wl <= lam + 2.5)]
            bands.append(inside.mean() if len(inside) else np.interp(lam, wl, v))
        out[stem] = colour.SpectralDistribution(dict(zip(SHAPE.wavelengths, bands)))
    return out


def corresponding(xyz, white, la):
    """CAM16 forward under `white`, inverse under D65; XYZ relative (Y_w = 1)."""
    spec = colour.XYZ_to_CAM16(xyz * 100, white * 100, la, Y_B, SURROUND)
    kept = colour.CAM_Specification_CAM16(J=spec.J, C=spec.C, h=spec.h)
    return colour.CAM16_to_XYZ(kept, D65 * 100, la, Y_B, SURROUND) / 100


def degree(la):
    return float(colour.appearance.ciecam02.degree_of_adaptation(SURROUND.F, la))


def stones():
    rows = []
    refl = reflectances()
    for light, sd in lights().items():
        sd = sd.copy().align(SHAPE)
        white = colour.sd_to_XYZ(colour.sd_ones(SHAPE), CMFS, sd) / 100
        for stem in STONES:
            xyz = colour.sd_to_XYZ(refl[stem], CMFS, sd) / 100
            for lw in WHITE_CD_M2:
                la = L_A_FRACTION * lw
                seen = corresponding(xyz, white, la)
                rows.append([stem, light, lw, la, *xyz, *white, *seen, degree(la)])
    return rows


def breneman():
    sys_path = os.path.join(ROOT, "data", "breneman1987")
    whites = {}
    for r in csv.reader(l for l in open(os.path.join(sys_path, "breneman1987_whites.csv"))
                        if not l.startswith("#")):
        if r[0] == "experiment":
            continue
        whites[int(r[0])] = (float(r[2]), float(r[3]), float(r[4]), float(r[5]), float(r[6]))
    def factor(name):
        return 0.09 if name in ("Red", "Brown", "Foliage", "Green", "Blue", "Purple") else 0.27
    def from_uv(u, v, y):
        xy = colour.Luv_uv_to_xy(np.array([u, v]))
        return colour.xyY_to_XYZ(np.array([xy[0], xy[1], y]))
    rows = []
    for r in csv.reader(l for l in open(os.path.join(sys_path, "breneman1987_corresponding.csv"))
                        if not l.startswith("#")):
        if r[0] == "experiment":
            continue
        e, sample, name = int(r[0]), int(r[1]), r[2]
        if e not in whites:
            continue
        tu, tv, ru, rv, lw = whites[e]
        f = factor(name)
        la = L_A_FRACTION * lw
        test = corresponding(from_uv(float(r[3]), float(r[4]), f), from_uv(tu, tv, 1.0), la)
        ref = corresponding(from_uv(float(r[5]), float(r[6]), f), from_uv(ru, rv, 1.0), la)
        rows.append([e, sample, *test, *ref])
    return rows


def write(name, header, comment, rows):
    with open(os.path.join(HERE, name), "w", newline="") as f:
        f.write(comment)
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        for r in rows:
            w.writerow([x if isinstance(x, str) or isinstance(x, int) else f"{x:.10g}" for x in r])


def main():
    assert colour.__version__ == EXPECTED_VERSION, colour.__version__
    # The oracle's own check: D65 under D65 is itself, and a CAM16 round trip is exact.
    for la in (0.5, 100.0):
        x = np.array([0.3, 0.25, 0.4])
        assert np.allclose(corresponding(x, D65, la), x, atol=1e-9)
    head = ("# CAM16 corresponding colours computed with colour-science %s; generated by "
            "data/cam16/make.py (see data/cam16/README.md).\n" % colour.__version__)
    write(
        "cam16_stones.csv",
        ["stone", "light", "white_cd_m2", "la_cd_m2", "x", "y", "z", "white_x", "white_y",
         "white_z", "d65_x", "d65_y", "d65_z", "d_cam16"],
        head + "# x,y,z: the stone under the light, relative (white_y = 1); d65_*: CAM16's "
        "corresponding colour under D65, same L_A, Y_b = 20, average surround.\n",
        stones(),
    )
    write(
        "cam16_breneman1987.csv",
        ["experiment", "sample", "test_x", "test_y", "test_z", "reference_x", "reference_y",
         "reference_z"],
        head + "# Per pair of data/breneman1987/breneman1987_corresponding.csv: CAM16's colour "
        "under D65 of the test sample (under the test white) and of the reference sample (under "
        "the reference white); L_A = 0.2 x the experiment's white luminance; the samples' "
        "luminance factors as breneman1987.rs takes them (0.27, or 0.09 for the dark names).\n",
        breneman(),
    )


if __name__ == "__main__":
    main()
