#!/usr/bin/env python3
"""What each kind of light costs on the Aosta facade, per sample, per ray and at equal noise.

The facade of `restauro scene aosta` is lit in turn by one light of each kind: the sun, an
isotropic point light, a point light with a measured distribution (IES), an area luminaire, a
uniform sky, the CIE traditional overcast sky and the CIE general sky (type 12). For each:

* `restauro bench tracer --scene-file` gives whole Whitted samples (depth 1) and path samples
  per CPU-second on one thread, and rays per CPU-second;
* two Whitted renders with different seeds give the noise of one sample: the variance of the
  luminance of a pixel is half the mean square difference of the two images, times the samples
  per pixel (relative to the mean luminance squared);
* the cost at equal noise is the CPU time per sample times that relative variance: the CPU time
  one pixel needs to reach a relative standard error of 1 (lower is better).

Needs numpy and OpenEXR (pip install numpy OpenEXR). Not run by CI. Usage:

    python3 bench/lights/run.py [--restauro target/release/restauro] [--out /tmp/restauro-lights]

prints a JSON document on standard output.
"""

import argparse
import json
import pathlib
import re
import shutil
import subprocess

import numpy as np
import OpenEXR

LIGHTS = {
    "sun": """kind = "sun"
elevation_deg = 40.0
azimuth_deg = 200.0
illuminance_lux = 100000.0
spectrum = "sunlight"
""",
    "point": """kind = "point"
position = [0.0, -12.0, 8.0]
intensity_cd = 100000.0
spectrum = "metal_halide"
""",
    "point-ies": """kind = "point"
position = [3.5, -5.0, 0.3]
aim = [3.5, 0.0, 14.0]
spectrum = "metal_halide"
ies = "photometry/asa_15m_r2.ies"
""",
    "area": """kind = "area"
corner = [1.5, -5.0, 0.3]
u = [4.0, 0.0, 0.0]
v = [0.0, 0.0, 2.0]
normal = [0.0, 1.0, 0.0]
luminance_cd_m2 = 5000.0
spectrum = "led"
""",
    "sky-uniform": """kind = "sky"
illuminance_lux = 15000.0
model = "uniform"
spectrum = "skylight"
""",
    "sky-cie-overcast": """kind = "sky"
preset = "overcast"
spectrum = "daylight"
""",
    "sky-cie-general-12": """kind = "sky"
illuminance_lux = 15000.0
model = "cie-general"
cie_type = 12
sun_elevation_deg = 40.0
sun_azimuth_deg = 200.0
""",
}


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def luminance(path):
    with OpenEXR.File(str(path)) as f:
        return np.asarray(f.parts[0].channels["Y"].pixels, dtype=np.float64)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--restauro", default="target/release/restauro")
    ap.add_argument("--out", default="/tmp/restauro-lights")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    exe = str(pathlib.Path(a.restauro).resolve())
    out = pathlib.Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    run([exe, "scene", "aosta", "--out", str(out / "aosta")])
    text = (out / "aosta" / "aosta.toml").read_text()
    # Everything before the first light: camera, render settings, spectra, materials, objects.
    base = text[: text.index("[[lights]]")]
    base = re.sub(r"\n#[^\n]*$", "", base.rstrip()) + "\n\n"
    report = {"benchmark": "lights", "scene": "aosta", "width": a.width, "height": a.height,
              "spp": a.spp, "lights": {}}
    for name, light in LIGHTS.items():
        scene = out / "aosta" / f"{name}.toml"
        scene.write_text(base + "[[lights]]\n" + light)
        bench = json.loads(run([exe, "bench", "tracer", "--scene-file", str(scene),
                                "--width", str(a.width), "--height", str(a.height),
                                "--spp", str(a.spp), "--repeats", str(a.repeats),
                                "--progress", "none"]))
        whitted = next(r for r in bench["whitted"] if r["threads"] == 1)
        path = next(r for r in bench["path"] if r["threads"] == 1)
        images = []
        for seed in (1, 2):
            seeded = out / "aosta" / f"{name}-seed{seed}.toml"
            seeded.write_text(re.sub(r"seed = \d+", f"seed = {seed}", scene.read_text()))
            dest = out / f"{name}-seed{seed}"
            run([exe, "render", str(seeded), "--in-process", "--out", str(dest),
                 "--width", str(a.width), "--height", str(a.height), "--spp", str(a.spp),
                 "--integrator", "whitted", "--progress", "none"])
            images.append(luminance(dest / f"{name}-seed{seed}.exr"))
        y1, y2 = images
        mean = float(np.mean((y1 + y2) / 2))
        variance_per_sample = float(np.mean((y1 - y2) ** 2) / 2) * a.spp
        relative_variance = variance_per_sample / mean**2
        cpu_per_sample = 1.0 / whitted["samples_per_cpu_s"]
        report["lights"][name] = {
            "whitted_samples_per_cpu_s": whitted["samples_per_cpu_s"],
            "whitted_rays_per_cpu_s": whitted["rays_per_cpu_s"],
            "whitted_rays_per_sample": whitted["rays"]
            / (a.width * a.height * a.spp * whitted["repetitions"]),
            "path_samples_per_cpu_s": path["samples_per_cpu_s"],
            "path_rays_per_cpu_s": path["rays_per_cpu_s"],
            "mean_luminance_cd_m2": mean,
            "relative_variance_per_sample": relative_variance,
            "cpu_us_at_unit_relative_error": cpu_per_sample * relative_variance * 1e6,
        }
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
