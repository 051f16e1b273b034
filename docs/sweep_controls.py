#!/usr/bin/env python3
"""Control volumes for the sweeping index (see docs/synthesis.md).

Usage: python3 docs/sweep_controls.py IMAGE OUT_DIR
Writes four 64x64x128 layered volumes (NRRD, R,G,B,Depth, type 1-b) cut from IMAGE shrunk
to 128x128, whose row r is depth r/127 along z:
  diag            V(x,y,z) = E((x+y) mod 128, z)  the diagonal sweep the rule is for
  sweepy          V(x,y,z) = E(x, z)              a sweep along y
  shifted_rows    V(x,y,z) = E((x+r(y)) mod 128, z), r random per y
  random_columns  V(x,y,z) = E(c(x,y), z), c random per (x, y)
Then: solidtex quality OUT_DIR/diag.nrrd --exemplar IMAGE --max-exemplar 128 --layered
Needs Pillow and numpy.
"""
import sys
import numpy as np
from PIL import Image


def write(path, colour):
    x, y, z, _ = colour.shape
    depth = np.broadcast_to((np.arange(z) / (z - 1))[None, None, :, None], (x, y, z, 1))
    samples = np.concatenate([colour, depth], axis=3).transpose(2, 1, 0, 3)
    header = (
        "NRRD0004\ntype: float\ndimension: 4\nsizes: 4 %d %d %d\nkinds: vector domain domain domain\n"
        "endian: little\nencoding: raw\nsolidtex_dims:=%d %d %d\nsolidtex_channels:=R,G,B,Depth\n"
        "solidtex_type:=1-b\n\n" % (x, y, z, x, y, z)
    )
    with open(path, "wb") as f:
        f.write(header.encode() + np.ascontiguousarray(samples).astype("<f4").tobytes())


def main():
    image, out = sys.argv[1], sys.argv[2]
    e = np.asarray(Image.open(image).convert("RGB").resize((128, 128), Image.LANCZOS), np.float32) / 255
    rng = np.random.default_rng(1)
    x = np.arange(64)[:, None, None]
    y = np.arange(64)[None, :, None]
    z = np.arange(128)[None, None, :]
    r = rng.integers(0, 128, size=64)[None, :, None]
    c = rng.integers(0, 128, size=(64, 64, 1))
    write(f"{out}/diag.nrrd", e[z, (x + y) % 128])
    write(f"{out}/sweepy.nrrd", e[z + 0 * y, x + 0 * y])
    write(f"{out}/shifted_rows.nrrd", e[z + 0 * x, (x + r) % 128])
    write(f"{out}/random_columns.nrrd", e[z + 0 * x, c + 0 * z])


if __name__ == "__main__":
    main()
