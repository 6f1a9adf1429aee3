"""Makes the JPEG test texture and what an independent decoder reads from it.

    python3 -m venv venv && venv/bin/pip install pillow==13.0.0
    venv/bin/python scene/tests/data/texture/make.py

`gradient.jpg`: 16 x 8 texels, red rising to the right, green downwards, blue constant,
baseline JPEG, quality 95, 4:2:0 chroma subsampling (Pillow's default for RGB), written by
Pillow (libjpeg-turbo). `gradient.txt`: the texels as Pillow decodes them again (libjpeg-turbo
with its default, "islow" IDCT and fancy upsampling), one row per line, "r,g,b" separated by
spaces: the reference restauro's decoder (zune-jpeg) is compared with.
"""

from pathlib import Path

from PIL import Image

here = Path(__file__).parent
w, h = 16, 8
image = Image.new("RGB", (w, h))
image.putdata([(16 * x + 8, 32 * y + 16, 90) for y in range(h) for x in range(w)])
image.save(here / "gradient.jpg", quality=95)
decoded = Image.open(here / "gradient.jpg").convert("RGB")
rows = [
    " ".join(",".join(str(c) for c in decoded.getpixel((x, y))) for x in range(w))
    for y in range(h)
]
(here / "gradient.txt").write_text("\n".join(rows) + "\n")
