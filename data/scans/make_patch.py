"""Writes weathered-patch.glb: a small textured glTF 2.0 "scan" of a weathered stone face made
here (no survey was taken), for the tests and for trying restauro on a textured model; and
weathered-patch.ply, the same patch as a laser scanner exports it: the same vertices and
normals with a colour per vertex (the photo averaged over each vertex's share of it), no
photo.

A 0.5 m x 0.5 m patch of a travertine face, 65 x 65 vertices (8192 triangles), relieved by up
to 12 mm (pitting and a worn band), with a 256 x 256 JPEG photo: warm stone, black crust in the
pits, a grey-green lichen colony and a rust stain, as a photogrammetry export would carry them
(positions, normals and one texture coordinate set; the photo in the .glb).

Deterministic: a fixed seed. Run with numpy and Pillow:
    python3 make_patch.py        # in data/scans/
"""
import io
import json
import struct

import numpy as np
from PIL import Image

N = 65           # vertices along each edge
SIZE_M = 0.5     # the patch's edge
TEX = 256        # the photo's edge in pixels
rng = np.random.default_rng(20261205)


def smooth_noise(n, scale, seed_rng):
    """Value noise: a coarse random grid bilinearly enlarged to n x n, in [0, 1]."""
    coarse = seed_rng.random((scale + 1, scale + 1))
    t = np.linspace(0, scale, n)
    i = np.minimum(t.astype(int), scale - 1)
    f = t - i
    rows = coarse[i] * (1 - f)[:, None] + coarse[i + 1] * f[:, None]
    return rows[:, i] * (1 - f) + rows[:, i + 1] * f


def fractal(n, seed_rng):
    total = sum(smooth_noise(n, 2 ** k, seed_rng) / 2 ** k for k in range(1, 6))
    return (total - total.min()) / (total.max() - total.min())


# The photo (rows from the top, as glTF's texture coordinates count them).
tone = fractal(TEX, rng)
pits = smooth_noise(TEX, 40, rng) > 0.85
lichen = fractal(TEX, rng) > 0.7
yy, xx = np.mgrid[0:TEX, 0:TEX] / TEX
rust = np.exp(-(((xx - 0.7) / 0.08) ** 2 + ((yy - 0.25) / 0.2) ** 2))
stone = np.array([196, 180, 150], float)
photo = stone * (0.8 + 0.35 * tone[..., None])
photo[pits] = photo[pits] * 0.25 + np.array([20, 18, 16]) * 0.75
photo[lichen] = photo[lichen] * 0.4 + np.array([118, 130, 96]) * 0.6
photo = photo * (1 - 0.5 * rust[..., None]) + np.array([150, 80, 40]) * 0.5 * rust[..., None]
jpeg = io.BytesIO()
photo8 = Image.fromarray(np.clip(photo, 0, 255).astype(np.uint8))
photo8.save(jpeg, "JPEG", quality=90)
jpeg = jpeg.getvalue()

# The relief: pits where the photo is dark, a worn band across the middle (z up in the file
# would be glTF's +Y: the face looks along +Z, so the relief is along +Z).
relief = fractal(N, rng) * 0.004
sample = np.linspace(0, TEX - 1, N).astype(int)
relief -= 0.008 * pits[np.ix_(sample, sample)]
v = np.linspace(0, 1, N)
relief -= 0.004 * np.exp(-((v[:, None] - 0.55) / 0.1) ** 2)
xs = (v - 0.5) * SIZE_M
positions = np.zeros((N, N, 3), np.float32)
positions[..., 0] = xs[None, :]
positions[..., 1] = -xs[:, None]          # rows run down the face
positions[..., 2] = relief
uv = np.zeros((N, N, 2), np.float32)
uv[..., 0] = v[None, :]
uv[..., 1] = v[:, None]
# Normals from the grid's central differences.
dz_dx = np.gradient(relief, xs, axis=1)
dz_dy = np.gradient(relief, -xs, axis=0)
normals = np.dstack([-dz_dx, -dz_dy, np.ones_like(relief)]).astype(np.float32)
normals /= np.linalg.norm(normals, axis=2, keepdims=True)
quads = [(r * N + c, r * N + c + 1, (r + 1) * N + c + 1, (r + 1) * N + c)
         for r in range(N - 1) for c in range(N - 1)]
# Counter-clockwise seen from +Z (rows run towards −Y).
indices = np.array([(a, d, c, a, c, b) for a, b, c, d in quads], np.uint32).ravel()

chunks = [positions.reshape(-1, 3).tobytes(), normals.reshape(-1, 3).tobytes(),
          uv.reshape(-1, 2).tobytes(), indices.tobytes(), jpeg]
offsets, binary = [], b""
for chunk in chunks:
    offsets.append(len(binary))
    binary += chunk + b"\0" * (-len(chunk) % 4)
p = positions.reshape(-1, 3)
gltf = {
    "asset": {"version": "2.0", "generator": "restauro data/scans/make_patch.py"},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0, "name": "weathered-patch"}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                "indices": 3, "material": 0}]}],
    "materials": [{"name": "travertine",
                   "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
    "textures": [{"source": 0}],
    "images": [{"bufferView": 4, "mimeType": "image/jpeg"}],
    "buffers": [{"byteLength": len(binary)}],
    "bufferViews": [{"buffer": 0, "byteOffset": o, "byteLength": len(c)}
                    for o, c in zip(offsets, chunks)],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": N * N, "type": "VEC3",
         "min": p.min(axis=0).tolist(), "max": p.max(axis=0).tolist()},
        {"bufferView": 1, "componentType": 5126, "count": N * N, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": N * N, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
    ],
}
text = json.dumps(gltf, separators=(",", ":")).encode()
text += b" " * (-len(text) % 4)
glb = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(binary))
glb += struct.pack("<II", len(text), 0x4E4F534A) + text
glb += struct.pack("<II", len(binary), 0x004E4942) + binary
open("weathered-patch.glb", "wb").write(glb)
print(f"weathered-patch.glb: {len(glb)} bytes, {len(indices) // 3} triangles")

# The scanner's export: binary little-endian PLY, the glTF's file coordinates (Y up), and a
# colour per vertex: the photo box-filtered down to the vertex grid.
colours = np.asarray(photo8.resize((N, N), Image.BOX), np.uint8).reshape(-1, 3)
header = (
    "ply\nformat binary_little_endian 1.0\n"
    "comment made by restauro data/scans/make_patch.py; Y up\n"
    f"element vertex {N * N}\n"
    "property float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    f"element face {len(indices) // 3}\n"
    "property list uchar int vertex_indices\nend_header\n"
).encode()
vertex = np.dtype([("p", "<f4", 3), ("n", "<f4", 3), ("c", "u1", 3)])
vertices = np.zeros(N * N, vertex)
vertices["p"], vertices["n"], vertices["c"] = p, normals.reshape(-1, 3), colours
face = np.dtype([("count", "u1"), ("i", "<i4", 3)])
faces = np.zeros(len(indices) // 3, face)
faces["count"], faces["i"] = 3, indices.reshape(-1, 3).astype(np.int32)
ply = header + vertices.tobytes() + faces.tobytes()
open("weathered-patch.ply", "wb").write(ply)
print(f"weathered-patch.ply: {len(ply)} bytes, {len(faces)} triangles")
