#!/usr/bin/env python3
"""Box-filters an sRGB PNG down by an integer factor in linear light: Fovea rendered at k× the
size and reduced this way is antialiased like a path tracer's box-filtered pixels, so a
comparison with Mitsuba measures shading rather than stair-stepped silhouettes.

    venv/bin/python tools/box_downsample.py ours-640x480.png ours.png 4
"""
import sys

import numpy as np
from PIL import Image


def load_linear(path):
    """An sRGB PNG as linear RGB floats."""
    c = np.asarray(Image.open(path).convert("RGB"), dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def save_srgb(lin, path):
    """Linear RGB floats as an 8-bit sRGB PNG (clipped to [0, 1])."""
    s = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * np.power(np.maximum(lin, 0), 1 / 2.4) - 0.055)
    Image.fromarray(np.round(np.clip(s, 0, 1) * 255).astype(np.uint8)).save(path)


def main():
    if len(sys.argv) != 4:
        raise SystemExit(__doc__)
    src, dst, k = sys.argv[1], sys.argv[2], int(sys.argv[3])
    lin = load_linear(src)
    h, w = lin.shape[0] // k, lin.shape[1] // k
    if k < 1 or h == 0 or w == 0 or lin.shape[0] % k or lin.shape[1] % k:
        raise SystemExit(f"{src}: {lin.shape[1]}x{lin.shape[0]} is not a multiple of {k}")
    save_srgb(lin.reshape(h, k, w, k, 3).mean(axis=(1, 3)), dst)


if __name__ == "__main__":
    main()
