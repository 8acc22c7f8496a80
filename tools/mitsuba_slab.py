#!/usr/bin/env python3
"""The dipole's level on its own geometry: Mitsuba 3 path-traces a thick slab of a Jensen 2001
material (rough dielectric boundary, homogeneous medium, as tools/mitsuba_reference.py builds
it) under a directional light from straight above, seen 30° off the normal, and prints the
mean radiance of the view in Fovea's units (×π) with its standard error. Compare with Fovea's
render of docs/bench/surfaces-truth/slab.json (a plane of the same material, same light and
view) over the centre of the frame:

    venv/bin/python tools/mitsuba_slab.py --preset marble --spp 1024
    fovea render --scene-file docs/bench/surfaces-truth/slab.json --preset reference --size 64x64 --no-marker --out slab.png

A thick slab is the semi-infinite medium the dipole assumes, so the two should agree within
the noise; where a bunny differs more, the cause is its shape, not the dipole's level.
"""
import argparse
import math
import os
import sys

import numpy as np


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--preset", default="marble")
    p.add_argument("--eta", type=float, default=1.3)
    p.add_argument("--roughness", type=float, default=0.3)
    p.add_argument("--thickness-mm", type=float, default=100.0)
    p.add_argument("--spp", type=int, default=1024)
    p.add_argument("--variant", default="llvm_ad_rgb")
    a = p.parse_args()
    import mitsuba as mi
    mi.set_variant(a.variant)
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from mitsuba_reference import material_dict
    mm = 10.0
    m = material_dict({"kind": "translucent", "preset": a.preset, "eta": a.eta, "roughness": a.roughness},
                      mm, False, "fovea")
    thick = a.thickness_mm / mm
    tilt = math.radians(30.0)
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": 100000, "rr_depth": 100000},
        "sensor": {"type": "perspective", "fov": 5,
                   "to_world": mi.ScalarTransform4f.look_at(origin=[0, 20 * math.cos(tilt), 20 * math.sin(tilt)],
                                                            target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": a.spp}},
        "sun": {"type": "directional", "direction": [0, -1, 0], "irradiance": {"type": "rgb", "value": [1, 1, 1]}},
        "slab": dict({"type": "cube", "to_world": mi.ScalarTransform4f.translate([0, -thick / 2, 0])
                      @ mi.ScalarTransform4f.scale([50, thick / 2, 50])}, **m),
    })
    img = np.array(mi.render(scene), dtype=np.float64)[..., :3] * math.pi
    n = img.shape[0] * img.shape[1]
    print(f"{a.preset}, η {a.eta}, roughness {a.roughness}, {a.spp} spp: mean (R, G, B) "
          f"{np.round(img.mean((0, 1)), 4).tolist()} ± {np.round(img.std((0, 1)) / math.sqrt(n), 4).tolist()}")


if __name__ == "__main__":
    main()
