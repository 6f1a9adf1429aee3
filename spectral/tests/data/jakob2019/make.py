"""Reference spectra for restauro's Jakob & Hanika (2019) RGB upsampling, made with colour-science.

Run from this folder with a Python that has colour-science, NumPy and SciPy:

    python3 make.py            # writes reference.csv beside this file

Nothing here is restauro's code: the target colours, the fits, the spectra and their XYZ are all
colour-science's (see README.md for versions and licence).

The set-up is the one restauro fits in (spectral/src/rgb_upsampling.rs):

* the spectral shape is restauro's grid, 380-780 nm in 5 nm steps (81 samples), so colour-science's
  dimensionless wavelength, numpy.linspace(0, 1, 81), is restauro's t = (lambda - 380) / 400;
* CIE 1931 2 degree colour-matching functions and CIE D65, both aligned to that shape;
* linear sRGB -> XYZ with the sRGB primaries and, as white, the chromaticity of D65 summed over that
  shape (colour.normalised_primary_matrix), so that RGB (1, 1, 1) is the perfect reflector under the
  illuminant the fit uses and a grey is a flat spectrum;
* the objective is colour-science's: the CIE 1976 colour difference between the target and the
  spectrum's colour under D65 (find_coefficients_Jakob2019). Its default stopping rule accepts a
  fit once the difference is at most JND/100 = 0.023; we ask for 1e-7 instead so that the reference
  is the converged optimum and a comparison tests the function, not the stopping rule. (Not
  tighter: colour-science uses the same threshold to accept each step of its continuation, and at
  1e-9 L-BFGS-B cannot meet it on the way to the saturated greens, whose fits then fail.)
"""

import csv
import warnings
from pathlib import Path

import numpy as np

import colour
from colour.colorimetry import sd_to_XYZ_integration
from colour.recovery import find_coefficients_Jakob2019, sd_Jakob2019
from colour.recovery.jakob2019 import dimensionalise_coefficients

warnings.filterwarnings("ignore")  # colour-science's "Matplotlib not available" notice

# The domain restauro fits: each linear channel clamped to [EPS, 1 - EPS], since the sigmoid never
# reaches 0 or 1.
EPS = 1e-4
MAX_ERROR = 1e-7

SHAPE = colour.SpectralShape(380, 780, 5)
CMFS = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(SHAPE)
D65 = colour.SDS_ILLUMINANTS["D65"].copy().align(SHAPE)

WHITE_XY = colour.XYZ_to_xy(sd_to_XYZ_integration(D65, CMFS))
SRGB = colour.models.RGB_COLOURSPACE_sRGB
RGB_TO_XYZ = colour.normalised_primary_matrix(SRGB.primaries, WHITE_XY)


def colorchecker_linear_srgb():
    """The 24 ColorChecker patches from colour-science's own dataset (xyY under D50, X-Rite's
    post-November-2014 values), adapted to D65 with Bradford and converted to linear sRGB by
    colour-science; then clamped to the fitted domain (the cyan patch lies outside sRGB)."""
    checker = colour.CCS_COLOURCHECKERS["ColorChecker24 - After November 2014"]
    out = []
    for name, xyY in checker.data.items():
        rgb = colour.XYZ_to_RGB(
            colour.xyY_to_XYZ(xyY),
            SRGB,
            illuminant=checker.illuminant,
            chromatic_adaptation_transform="Bradford",
            apply_cctf_encoding=False,
        )
        out.append((name, rgb))
    return out


def extra_linear_srgb():
    """Greys, saturated colours well inside the sRGB gamut, and the sRGB primaries themselves."""
    out = [(f"grey {g}", np.array([g, g, g])) for g in (0.02, 0.18, 0.5, 0.9)]
    out += [
        ("saturated red", np.array([0.8, 0.05, 0.05])),
        ("saturated green", np.array([0.05, 0.6, 0.05])),
        ("saturated blue", np.array([0.05, 0.05, 0.7])),
        ("saturated yellow", np.array([0.9, 0.8, 0.05])),
        ("saturated cyan", np.array([0.05, 0.7, 0.8])),
        ("saturated magenta", np.array([0.7, 0.05, 0.8])),
        ("srgb red", np.array([1.0, 0.0, 0.0])),
        ("srgb green", np.array([0.0, 1.0, 0.0])),
        ("srgb blue", np.array([0.0, 0.0, 1.0])),
    ]
    return out


def main():
    wavelengths = SHAPE.wavelengths
    assert len(wavelengths) == 81
    header = ["name", "r", "g", "b", "target_X", "target_Y", "target_Z", "delta_e"]
    header += ["c0", "c1", "c2", "X", "Y", "Z"] + [f"{w:g}" for w in wavelengths]
    rows = []
    for name, rgb in colorchecker_linear_srgb() + extra_linear_srgb():
        rgb = np.clip(rgb, EPS, 1 - EPS)
        target = RGB_TO_XYZ @ rgb
        # Dimensionless coefficients for t = linspace(0, 1, 81), and the CIE 1976 difference.
        c, delta_e = find_coefficients_Jakob2019(
            target, CMFS, D65, max_error=MAX_ERROR, dimensionalise=False
        )
        sd = sd_Jakob2019(dimensionalise_coefficients(c, SHAPE), SHAPE)
        xyz = colour.sd_to_XYZ(sd, CMFS, D65, method="Integration") / 100
        row = [name.replace(",", " ")] + list(rgb) + list(target) + [delta_e] + list(c)
        rows.append(row + list(xyz) + list(sd.values))
        print(f"{name:20s} rgb {rgb.round(4)} delta E {delta_e:.2e}")
    out = Path(__file__).with_name("reference.csv")
    with out.open("w", newline="") as f:
        f.write(
            "# Jakob & Hanika (2019) spectra by colour-science "
            f"{colour.__version__} (numpy {np.__version__}); made by make.py, see README.md.\n"
            "# r g b: linear sRGB (clamped to [1e-4, 1 - 1e-4]); target_XYZ: its XYZ, Y = 1 for "
            "white; delta_e: CIE 1976 difference of the fit; c0 c1 c2: coefficients for "
            "t = (lambda - 380) / 400; X Y Z: the spectrum's XYZ under D65, CIE 1931 2 degree, "
            "Y = 1 for white; then the spectrum at 380..780 nm.\n"
        )
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(header)
        for row in rows:
            writer.writerow([row[0]] + [repr(float(v)) for v in row[1:]])
    print(f"wrote {len(rows)} colours to {out}")


if __name__ == "__main__":
    main()
