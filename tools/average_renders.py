#!/usr/bin/env python3
"""Averages sRGB PNG renders of the same frame in linear light, each weighted by its sample
count: two Mitsuba runs with disjoint seeds (`mitsuba_reference.py --seed-offset`) make one
reference with the samples of both, without rendering the first again.

    venv/bin/python tools/average_renders.py out.png truth-8k.png:8192 truth2-8k.png:8192
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from box_downsample import load_linear, save_srgb  # noqa: E402


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    total, weight = None, 0.0
    for arg in sys.argv[2:]:
        path, _, spp = arg.rpartition(":")
        if not path or not spp.isdigit() or int(spp) == 0:
            raise SystemExit(f"{arg}: expected PATH:SAMPLES\n\n{__doc__}")
        lin = load_linear(path) * int(spp)
        if total is not None and lin.shape != total.shape:
            raise SystemExit(f"{path}: {lin.shape[1]}x{lin.shape[0]} differs from the first image")
        total = lin if total is None else total + lin
        weight += int(spp)
    save_srgb(total / weight, sys.argv[1])


if __name__ == "__main__":
    main()
