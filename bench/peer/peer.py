"""The peer comparison's shared code: restauro's spectra and photometry re-read from the
repository's own data files, and a restauro scene file (the subset bench/peer/scene uses)
turned into the same scene for Mitsuba 3.

Everything numeric comes from the restauro scene file, its OBJ and restauro's data/ folder:

* Reflectances: the shipped CSV (data/spectra/NAME.csv) resampled onto restauro's 81 bands
  (380–780 nm every 5 nm) by restauro's rule (spectral/src/tabulated.rs): where two or more
  samples fall inside a band's ±2.5 nm window, the mean of the piecewise-linear curve over the
  window (clipped to the data); else linear interpolation at the band's centre; the first and
  last measured values held beyond the data.
* Illuminants: the CIE table restauro embeds (data/cie/cie_illuminants_..._5nm_380-780.csv).
* Photometry (restauro spectral/src/photometry.rs, Rossi et al. 2004 Eqs. 2 and 8): a light of
  photometric value P (cd, lux, or cd/m²) and spectral shape S(λ) has the spectral quantity
  P · S(λ) / (K_m Σ S(λ) V(λ) Δλ), K_m = 683 lm/W, Δλ = 5 nm, V = CIE 1924 photopic (= ȳ of
  CIE 1931), the sum over the 81 bands. The sun's illuminance is on a plane normal to its rays
  (Mitsuba's `directional` `irradiance` is the same quantity); a point's intensity is in cd
  (Mitsuba's `point` `intensity`, W·sr⁻¹·nm⁻¹); a uniform sky of diffuse horizontal illuminance
  E_h has the luminance E_h / π (Mitsuba's `constant` `radiance`).
* Each band value becomes a node of a piecewise-linear Mitsuba spectrum over 380–780 nm (zero
  outside, where ȳ < 4·10⁻⁵).

Luminance: restauro's EXR holds absolute Y = K_m Σ L(λ) ȳ(λ) Δλ in cd/m². Mitsuba's XYZ film
divides ∫ L ȳ dλ by ∫ ȳ dλ (MI_CIE_Y_NORMALIZATION = 1/106.857 over its 360–830 nm table), so
its luminance is K_m / MI_CIE_Y_NORMALIZATION · Y_mitsuba.
"""

from __future__ import annotations

import math
import os
import pathlib
import subprocess
import tempfile
import tomllib

HERE = pathlib.Path(__file__).resolve().parent
REPO = HERE.parent.parent
DATA = REPO / "data"
SCENE = HERE / "scene" / "stones.toml"
RESTAURO = REPO / "target" / "release" / "restauro"

K_M = 683.0
STEP_NM = 5.0
BANDS = [380.0 + STEP_NM * i for i in range(81)]
LLVM_CANDIDATES = [
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/llvm-19/lib/libLLVM.so.1",
    "/usr/lib/aarch64-linux-gnu/libLLVM-19.so",
]


# ---------------------------------------------------------------------------------------------
# Spectra, as restauro reads them


def read_csv(path: pathlib.Path) -> tuple[list[str], list[list[float]]]:
    """A restauro data CSV: `#` comments, one header line, then numbers. Returns the header's
    names and the rows."""
    header: list[str] | None = None
    rows = []
    for line in path.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = [f.strip() for f in line.split(",")]
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            if header is None and not rows:
                header = fields
                continue
            raise
    return header or [], rows


def _interpolate(w: list[float], v: list[float], x: float) -> float:
    # Linear interpolation inside the data (the caller keeps x inside).
    import bisect

    j = bisect.bisect_right(w, x)
    if j <= 0:
        return v[0]
    if j >= len(w):
        return v[-1]
    t = (x - w[j - 1]) / (w[j] - w[j - 1])
    return v[j - 1] + t * (v[j] - v[j - 1])


def _integrate(w: list[float], v: list[float], a: float, b: float) -> float:
    import bisect

    total, x, y = 0.0, a, _interpolate(w, v, a)
    start = bisect.bisect_right(w, a)
    for knot in w[start:]:
        if knot >= b:
            break
        yk = _interpolate(w, v, knot)
        total += 0.5 * (y + yk) * (knot - x)
        x, y = knot, yk
    yb = _interpolate(w, v, b)
    return total + 0.5 * (y + yb) * (b - x)


def resample(w: list[float], v: list[float]) -> list[float]:
    """restauro's resampling onto the 81 bands (spectral/src/tabulated.rs, HoldEnds)."""
    import bisect

    first, last, half = w[0], w[-1], STEP_NM / 2
    out = []
    for lam in BANDS:
        if lam < first:
            out.append(v[0])
        elif lam > last:
            out.append(v[-1])
        else:
            inside = bisect.bisect_left(w, lam + half) - bisect.bisect_right(w, lam - half)
            if inside >= 2:
                a, b = max(lam - half, first), min(lam + half, last)
                out.append(_integrate(w, v, a, b) / (b - a))
            else:
                out.append(_interpolate(w, v, lam))
    return out


def shipped(name: str) -> list[float]:
    _, rows = read_csv(DATA / "spectra" / f"{name}.csv")
    return resample([r[0] for r in rows], [r[1] for r in rows])


def _cie_table(file: str) -> dict[str, list[float]]:
    header, rows = read_csv(DATA / "cie" / file)
    assert [r[0] for r in rows] == BANDS, file
    return {name: [r[k] for r in rows] for k, name in enumerate(header) if k > 0}


def photopic_v() -> list[float]:
    return _cie_table("cie1924_photopic_V_5nm_380-780.csv")["photopic_V"]


def illuminant(name: str) -> list[float]:
    table = _cie_table("cie_illuminants_A_B_C_D50_D55_D65_D75_E_5nm_380-780.csv")
    if name.upper() not in table:
        raise SystemExit(f"illuminant {name}: only the tabulated {sorted(table)} are supported here")
    return table[name.upper()]


def spectrum(scene: dict, name: str) -> list[float]:
    """The 81 band values of a named spectrum of the scene file's [spectra]."""
    form = scene["spectra"][name]
    if isinstance(form, str):
        return shipped(form)
    if "illuminant" in form:
        return illuminant(form["illuminant"])
    if "constant" in form:
        return [float(form["constant"])] * 81
    raise SystemExit(f"spectrum {name}: form {form} is not supported by bench/peer")


def per_lumen(spd: list[float]) -> list[float]:
    """S(λ) / (K_m Σ S V Δλ): the spectral quantity of one photometric unit (restauro's
    LuminousSpectrum::per_lumen; the scaling to 100 at 555 nm cancels)."""
    p555 = spd[BANDS.index(555.0)]
    rel = [s * 100.0 / p555 for s in spd]
    integral = K_M * sum(r * v for r, v in zip(rel, photopic_v())) * STEP_NM
    return [r / integral for r in rel]


def luminance(radiance: list[float]) -> float:
    """restauro's luminance of an 81-band spectral radiance: K_m Σ L ȳ Δλ."""
    return K_M * sum(r * v for r, v in zip(radiance, photopic_v())) * STEP_NM


# ---------------------------------------------------------------------------------------------
# The scene file


def load_toml(path: pathlib.Path = SCENE) -> dict:
    return tomllib.loads(path.read_text())


def read_obj(path: pathlib.Path) -> dict[str, tuple[list, list]]:
    """Triangles of an OBJ by part (usemtl, else o/g, else `default`): part → (vertices, faces),
    each part's vertices re-indexed from 0. Polygons are fanned, as restauro does."""
    verts: list[tuple[float, float, float]] = []
    parts: dict[str, list[tuple[int, int, int]]] = {}
    usemtl = group = None
    for line in path.read_text().splitlines():
        f = line.split()
        if not f or f[0].startswith("#"):
            continue
        if f[0] == "v":
            verts.append(tuple(float(x) for x in f[1:4]))
        elif f[0] == "usemtl":
            usemtl = f[1]
        elif f[0] in ("o", "g"):
            group = f[1] if len(f) > 1 else None
        elif f[0] == "f":
            idx = [int(x.split("/")[0]) for x in f[1:]]
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
            tris = parts.setdefault(usemtl or group or "default", [])
            for k in range(1, len(idx) - 1):
                tris.append((idx[0], idx[k], idx[k + 1]))
    out = {}
    for name, tris in parts.items():
        used = sorted({i for t in tris for i in t})
        remap = {old: new for new, old in enumerate(used)}
        out[name] = ([verts[i] for i in used], [tuple(remap[i] for i in t) for t in tris])
    return out


def sun_direction(light: dict) -> list[float]:
    """restauro's unit vector towards the sun (scene/src/sun.rs): azimuth from north (+Y)
    towards east (+X)."""
    if "site" in light or "preset" in light:
        raise SystemExit("bench/peer supports a sun given by illuminance_lux, azimuth, elevation")
    az = math.radians(light.get("azimuth_deg", 180.0))
    el = math.radians(light["elevation_deg"])
    return [math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el)]


def mitsuba_spectrum(values: list[float]) -> dict:
    return {"type": "spectrum", "value": list(zip(BANDS, values))}


def mitsuba_dict(
    scene: dict,
    scene_dir: pathlib.Path,
    mesh_dir: pathlib.Path,
    integrator: str,
    width: int,
    height: int,
    spp: int,
    lights: set[str] | None = None,
) -> dict:
    """The scene as a Mitsuba 3 dictionary. `integrator`: `direct` (against restauro's
    whitted) or `path` (max_depth = restauro's + 1). `lights` keeps only these kinds (for
    diagnosis). Meshes are written as OBJ files, one per part, into `mesh_dir`."""
    import mitsuba as mi

    cam = scene["camera"]
    if "viewpoint" in cam:
        raise SystemExit("bench/peer: give the camera as position and target")
    d: dict = {
        "type": "scene",
        "camera": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": float(cam.get("vertical_fov_deg", 45.0)),
            "to_world": mi.ScalarTransform4f().look_at(
                origin=cam["position"], target=cam["target"], up=cam.get("up", [0, 0, 1])
            ),
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "pixel_format": "xyz",
                "rfilter": {"type": "box"},
            },
            "sampler": {"type": "independent", "sample_count": spp},
        },
    }
    depth = scene.get("render", {}).get("max_depth", 5)
    if integrator == "direct":
        # Mitsuba's defaults: one emitter sample (one emitter picked at random, one shadow ray)
        # and one cosine-weighted BSDF sample (which sees the sky), combined by MIS: two
        # secondary rays per camera sample, where restauro's whitted traces three here (one
        # shadow ray per light, sun and point, and one cosine-weighted sky ray). More emitter
        # samples would be nearer in work, but Mitsuba 3.9's `direct` then counts delta emitters
        # (sun, point) emitter_samples times over (mitsuba3 issue #1861, fix in PR #1863), so
        # its image would be wrong; the comparison is conservative for restauro.
        d["integrator"] = {"type": "direct", "emitter_samples": 1, "bsdf_samples": 1}
    elif integrator == "path":
        if depth == 0:
            raise SystemExit("bench/peer: give a max_depth (Mitsuba's path needs a cap here)")
        d["integrator"] = {"type": "path", "max_depth": depth + 1}
    else:
        raise ValueError(integrator)

    for name, mat in scene.get("materials", {}).items():
        if mat["model"] != "lambert":
            raise SystemExit(f"material {name}: bench/peer supports lambert only")
    for obj in scene.get("objects", []):
        if obj.get("transform") or obj.get("replaces"):
            raise SystemExit(f"object {obj['name']}: bench/peer supports untransformed meshes")
        mesh = scene_dir / obj["mesh"]
        if mesh.suffix.lower() != ".obj" or obj.get("up_axis", "z") != "z":
            raise SystemExit(f"object {obj['name']}: bench/peer supports Z-up OBJ meshes")
        for part, (verts, faces) in read_obj(mesh).items():
            material = obj.get("materials", {}).get(part, obj.get("material"))
            rho = spectrum(scene, scene["materials"][material]["reflectance"])
            path = mesh_dir / f"{obj['name']}-{part}.obj"
            lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in verts]
            lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
            path.write_text("\n".join(lines) + "\n")
            d[f"{obj['name']}-{part}"] = {
                "type": "obj",
                "filename": str(path),
                # restauro shades with the geometric normal of each triangle.
                "face_normals": True,
                "bsdf": {"type": "diffuse", "reflectance": mitsuba_spectrum(rho)},
            }

    for k, light in enumerate(scene["lights"]):
        kind = light["kind"]
        if lights is not None and kind not in lights:
            continue
        unit = per_lumen(spectrum(scene, light["spectrum"]))
        if kind == "sun":
            e = float(light["illuminance_lux"])
            d[f"light{k}"] = {
                "type": "directional",
                "direction": [-c for c in sun_direction(light)],
                "irradiance": mitsuba_spectrum([e * u for u in unit]),
            }
        elif kind == "point":
            if "ies" in light or "flux_lm" in light:
                raise SystemExit("bench/peer supports an isotropic point with intensity_cd")
            i = float(light["intensity_cd"])
            d[f"light{k}"] = {
                "type": "point",
                "position": light["position"],
                "intensity": mitsuba_spectrum([i * u for u in unit]),
            }
        elif kind == "sky":
            if light.get("model") != "uniform" or "ground_reflectance" in light:
                raise SystemExit("bench/peer supports a uniform sky without ground_reflectance")
            l_v = float(light["illuminance_lux"]) / math.pi
            d[f"light{k}"] = {
                "type": "constant",
                "radiance": mitsuba_spectrum([l_v * u for u in unit]),
            }
        else:
            raise SystemExit(f"light kind {kind}: not supported by bench/peer")
    return d


# ---------------------------------------------------------------------------------------------
# Mitsuba


def setup_mitsuba():
    """Imports Mitsuba with the llvm_ad_spectral variant, pointing Dr.Jit at Debian's LLVM 19
    unless DRJIT_LIBLLVM_PATH is set already."""
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        for c in LLVM_CANDIDATES:
            if os.path.exists(c):
                os.environ["DRJIT_LIBLLVM_PATH"] = c
                break
    import mitsuba as mi

    mi.set_variant("llvm_ad_spectral")
    return mi


def mitsuba_luminance_factor(mi) -> float:
    """cd/m² per unit of Mitsuba's Y."""
    return K_M / mi.MI_CIE_Y_NORMALIZATION


def mitsuba_render_y(mi, scene, spp: int, seed: int = 0, pass_spp: int = 64):
    """Mitsuba's luminance image (cd/m², numpy, rows top to bottom), rendered in passes of at
    most `pass_spp` samples per pixel (bounding the wavefront's memory) and averaged."""
    import numpy as np

    total, done, k = None, 0, 0
    while done < spp:
        n = min(pass_spp, spp - done)
        img = np.array(mi.render(scene, spp=n, seed=seed * 100003 + k))
        y = img[:, :, 1].astype(np.float64) * n
        total = y if total is None else total + y
        done += n
        k += 1
    return total / spp * mitsuba_luminance_factor(mi)


# ---------------------------------------------------------------------------------------------
# restauro


def restauro_render_y(
    mi,
    scene_file: pathlib.Path,
    integrator: str,
    width: int,
    height: int,
    spp: int,
    restauro: pathlib.Path = RESTAURO,
):
    """restauro's luminance image (cd/m², numpy): `restauro render --in-process`, the EXR's Y."""
    import numpy as np

    with tempfile.TemporaryDirectory() as out:
        subprocess.run(
            [str(restauro), "render", str(scene_file), "--in-process", "--out", out,
             "--width", str(width), "--height", str(height), "--spp", str(spp),
             "--integrator", integrator, "--progress", "none", "--retinex-paths", "1"],
            check=True, stdout=subprocess.DEVNULL,
        )
        exr = pathlib.Path(out) / f"{scene_file.stem}.exr"
        bitmap = mi.Bitmap(str(exr))
        names = [field.name for field in bitmap.struct_()]
        return np.array(bitmap, dtype=np.float64)[:, :, names.index("Y")]


# ---------------------------------------------------------------------------------------------
# Comparison


def blocks(a, block: int = 8):
    """The means of the block × block tiles of an image (a partial last row or column left out)."""
    h, w = a.shape
    hb, wb = h // block, w // block
    return a[: hb * block, : wb * block].reshape(hb, block, wb, block).mean(axis=(1, 3))


def agreement(a, b, a2=None, b2=None, block: int = 8) -> dict:
    """Means of two luminance images and their differences: the whole image, and the 8×8
    blocks (each block's relative difference (a − b)/b). With a second, independent render of
    each (a2, b2), also the mean absolute block difference that their noise alone would give."""
    import numpy as np

    ba, bb = blocks(a, block), blocks(b, block)
    ok = bb > 0
    rel = (ba[ok] - bb[ok]) / bb[ok]
    out = {
        "mean_a_cd_m2": float(a.mean()),
        "mean_b_cd_m2": float(b.mean()),
        "relative_difference": float(a.mean() / b.mean() - 1.0),
        "blocks": int(ok.sum()),
        "block_mean_relative_difference": float(rel.mean()),
        "block_mean_abs_relative_difference": float(np.abs(rel).mean()),
        "block_max_abs_relative_difference": float(np.abs(rel).max()),
    }
    if a2 is not None and b2 is not None:
        na = (ba[ok] - blocks(a2, block)[ok]) / bb[ok]
        nb = (bb[ok] - blocks(b2, block)[ok]) / bb[ok]
        # na/√2 and nb/√2 have the noise of one render each, so (na − nb)/√2 has the noise of
        # the difference of the two renderers: its mean absolute value is what noise alone
        # gives (E|N(0, σ_a² + σ_b²)| block by block).
        out["block_mean_abs_relative_difference_from_noise"] = float(
            np.abs(na - nb).mean() / np.sqrt(2)
        )
    return out
