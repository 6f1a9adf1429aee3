#!/usr/bin/env python3
"""How restauro's cost grows with the image, the lights and the farm (issue 21, item 6).

* Image size: `restauro bench tracer --scene aosta` at 320×240, 1280×720 and 3840×2160 (4, 4
  and 1 samples per pixel): whole Whitted and path samples per CPU-second on one and two
  threads, and the two-thread speed-up in wall time.
* Lights: the Aosta facade lit by 1, 4 and 16 point lights (`--scene-file`), 640×360, 4 samples
  per pixel: samples and rays per CPU-second.
* The farm: `restauro bench cluster` (an embedded coordinator and two workers on loopback):
  tiles delivered per second, and the throughput against one process.

Plain Python 3, no packages. Not run by CI. Usage:

    python3 bench/growth/run.py [--restauro target/release/restauro] [--out /tmp/restauro-growth]

prints a JSON document on standard output.
"""

import argparse
import json
import pathlib
import shutil
import subprocess

SIZES = [(320, 240, 4), (1280, 720, 4), (3840, 2160, 1)]
LIGHT_COUNTS = [1, 4, 16]


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def tracer(exe, *extra):
    return json.loads(run([exe, "bench", "tracer", "--progress", "none", *extra]))


def rates(bench):
    """Samples and rays per CPU-second by thread count, and the two-thread wall speed-up."""
    out = {}
    for integrator in ("whitted", "path"):
        runs = {r["threads"]: r for r in bench[integrator]}
        out[integrator] = {
            "samples_per_cpu_s_1_thread": runs[1]["samples_per_cpu_s"],
            "samples_per_cpu_s_2_threads": runs[2]["samples_per_cpu_s"],
            "rays_per_cpu_s_1_thread": runs[1]["rays_per_cpu_s"],
            "speedup_2_threads": (runs[1]["wall_s"] / runs[1]["repetitions"])
            / (runs[2]["wall_s"] / runs[2]["repetitions"]),
        }
    return out


def point_lights(n):
    """`n` isotropic point lights on a line 12 m in front of the facade, 8 m up, sharing
    200 000 cd between them so that the image stays equally bright."""
    lights = []
    for i in range(n):
        x = -16.0 + 32.0 * (i + 0.5) / n
        lights.append(
            f'[[lights]]\nkind = "point"\nposition = [{x:.3f}, -12.0, 8.0]\n'
            f'intensity_cd = {200000.0 / n:.3f}\nspectrum = "metal_halide"\n'
        )
    return "\n".join(lights)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--restauro", default="target/release/restauro")
    ap.add_argument("--out", default="/tmp/restauro-growth")
    ap.add_argument("--repeats", type=int, default=2)
    a = ap.parse_args()
    exe = str(pathlib.Path(a.restauro).resolve())
    out = pathlib.Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    reps = ["--repeats", str(a.repeats)]
    report = {"benchmark": "growth", "sizes": [], "lights": [], "cluster": None}
    for w, h, spp in SIZES:
        b = tracer(exe, "--scene", "aosta", "--width", str(w), "--height", str(h),
                   "--spp", str(spp), *reps)
        report["sizes"].append({"width": w, "height": h, "spp": spp, **rates(b)})
    run([exe, "scene", "aosta", "--out", str(out / "aosta")])
    text = (out / "aosta" / "aosta.toml").read_text()
    base = text[: text.index("[[lights]]")]
    for n in LIGHT_COUNTS:
        scene = out / "aosta" / f"points-{n}.toml"
        scene.write_text(base + point_lights(n))
        b = tracer(exe, "--scene-file", str(scene), "--width", "640", "--height", "360",
                   "--spp", "4", *reps)
        whitted = next(r for r in b["whitted"] if r["threads"] == 1)
        report["lights"].append({
            "lights": n,
            "whitted_rays_per_sample": whitted["rays"]
            / (640 * 360 * 4 * whitted["repetitions"]),
            **rates(b),
        })
    c = json.loads(run([exe, "bench", "cluster", "--width", "960", "--height", "540",
                        "--spp", "16", "--repeats", "1", "--progress", "none"]))
    report["cluster"] = {k: c[k] for k in ("width", "height", "samples_per_pixel", "tiles",
                                           "cluster_median_seconds", "in_process_median_seconds",
                                           "throughput_ratio", "cluster_tiles_per_second")}
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
