#!/usr/bin/env python3
"""Offline: FLIP error map of a test image against a reference, as a PNG (NVIDIA's flip-evaluator).

    pip install flip-evaluator pillow numpy
    tools/error_map.py reference.png test.png out.png [--ppd 12.6]
"""
import argparse

import flip_evaluator as flip
import numpy as np
from PIL import Image

p = argparse.ArgumentParser(description=__doc__)
p.add_argument("reference")
p.add_argument("test")
p.add_argument("out")
p.add_argument("--ppd", type=float, default=12.6, help="pixels per degree (53 cm, 640 px wide, at 60 cm: 12.6)")
a = p.parse_args()
ref = np.asarray(Image.open(a.reference).convert("RGB"), dtype=np.float32) / 255.0
test = np.asarray(Image.open(a.test).convert("RGB"), dtype=np.float32) / 255.0
error_map, mean, _ = flip.evaluate(ref, test, "LDR", applyMagma=True, parameters={"ppd": a.ppd})
Image.fromarray((np.clip(error_map, 0, 1) * 255).astype(np.uint8)).save(a.out)
print(f"mean FLIP {mean:.4f} -> {a.out}")
