#!/usr/bin/env python3
"""Offline physical ground truth: render a Fovea scene file with Mitsuba 3's volumetric path
tracer, in Fovea's units, for `fovea bench --against` (not part of CI).

    python3 -m venv venv && venv/bin/pip install mitsuba numpy
    (Debian 12: apt-get install libllvm19 for the fast llvm_ad_rgb variant; scalar_rgb works as is)
    venv/bin/python tools/mitsuba_reference.py assets/scenes/bunny-marble.json ref.exr \
        --width 320 --height 240 --spp 1024 [--variant llvm_ad_rgb] [--diffuse-only]

Writes ref.exr (linear RGB in Fovea's display units) and ref.png (sRGB, what Fovea's frames
are), plus ref.json with the settings used.

How the scene is matched (docs/bench/ground-truth.md says more):
* camera: the same pinhole (eye, target, up, vertical field of view), box pixel filter;
* units: Fovea reports radiance ×π (a white Lambertian surface under unit irradiance shows 1),
  so the Mitsuba image is multiplied by π; the directional light's irradiance is
  color × intensity; an area light of exitance M has radiance M/π; Fovea's constant ambient
  (a fraction of the light, albedo-weighted) becomes a constant environment of radiance
  ambient × light / π (Mitsuba shadows it, Fovea does not: a small, stated difference);
* translucent materials: a rough dielectric boundary (GGX, α = roughness², η) around a homogeneous medium with
  σt = σ's + σa and single-scattering albedo σ's/σt per channel, isotropic phase function
  (Jensen's reduced coefficients), scaled from mm⁻¹ to scene units by mm_per_unit;
* opaque materials: Fovea's own surface model (`--surfaces fovea`, the default:
  tools/mitsuba_fovea_surface.py, Lambert scaled by what the GGX lobe leaves + GGX), so the
  comparison measures light transport (shadows, interreflection, subsurface) and not a choice of
  BRDF; or Disney's principled BSDF (`--surfaces principled`: base colour, roughness, metallic,
  specular from the IOR), which adds retro-reflection; emitters: area lights;
* background: pixels the camera ray leaves the scene through get Fovea's background colour.
"""
import argparse
import json
import math
import os

import numpy as np

JENSEN_2001 = {  # σ's, σa in mm⁻¹ (R, G, B): Jensen et al. 2001, Figure 5, as in src/scene/material.rs
    "apple": ([2.29, 2.39, 1.97], [0.0030, 0.0034, 0.046]),
    "chicken1": ([0.15, 0.21, 0.38], [0.015, 0.077, 0.19]),
    "chicken2": ([0.19, 0.25, 0.32], [0.018, 0.088, 0.20]),
    "cream": ([7.38, 5.47, 3.15], [0.0002, 0.0028, 0.0163]),
    "ketchup": ([0.18, 0.07, 0.03], [0.061, 0.97, 1.45]),
    "marble": ([2.19, 2.62, 3.00], [0.0021, 0.0041, 0.0071]),
    "potato": ([0.68, 0.70, 0.55], [0.0024, 0.0090, 0.12]),
    "skimmilk": ([0.70, 1.22, 1.90], [0.0014, 0.0025, 0.0142]),
    "skin1": ([0.74, 0.88, 1.01], [0.032, 0.17, 0.48]),
    "skin2": ([1.09, 1.59, 1.79], [0.013, 0.070, 0.145]),
    "wholemilk": ([2.55, 3.21, 3.77], [0.0011, 0.0024, 0.014]),
}


def srgb_encode(linear):
    c = np.clip(linear, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def srgb_decode(byte):
    c = byte / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def object_transform(mi, o):
    t = o.get("translate", [0, 0, 0])
    return (mi.ScalarTransform4f.translate(t)
            @ mi.ScalarTransform4f.rotate([0, 1, 0], o.get("rotate_y_deg", 0.0))
            @ mi.ScalarTransform4f.scale(o.get("scale", 1.0)))


def quad_transform(mi, corners):
    c = [np.array(p, dtype=float) for p in corners]
    u, v = c[1] - c[0], c[3] - c[0]
    n = np.cross(u, v)
    n /= np.linalg.norm(n)
    centre = c[0] + (u + v) / 2
    m = np.identity(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = u / 2, v / 2, n, centre
    return mi.ScalarTransform4f(m.tolist())


def material_dict(spec, mm_per_unit, diffuse_only, surfaces):
    kind = spec["kind"]
    # Fovea's surfaces (docs/scenes.md): GGX with α = roughness², clamped like Fovea's
    # optics::specular::MIN_ALPHA. Opaque: a rough dielectric coating over a diffuse base
    # (roughplastic, IOR as given), or a rough conductor with the base colour as its specular
    # reflectance when metallic; translucent: a rough dielectric boundary (roughdielectric).
    alpha = max(spec.get("roughness", 0.3 if kind == "translucent" else 0.5) ** 2, 0.002)
    if kind == "opaque":
        if diffuse_only:
            return {"bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": spec["albedo"]}}}
        # Disney's principled BSDF (with --surfaces principled) is the same family as Fovea's
        # (UE4's) surface: a diffuse base plus a GGX lobe with F0 = 0.08 × specular (0.04 at
        # 0.5, η 1.5), metals taking their colour from the base; its diffuse part adds
        # retro-reflection and keeps the lobe's share (+24% on a rough floor). (roughplastic, a
        # physically coated layer, compresses the diffuse light by 1/η²: another model again.)
        ior = spec.get("ior", 1.5)
        f0 = ((ior - 1) / (ior + 1)) ** 2
        if surfaces == "fovea":
            r, g, b = spec["albedo"]
            return {"bsdf": {"type": "fovea_surface", "r": r, "g": g, "b": b, "alpha": alpha,
                             "f0": f0, "metallic": spec.get("metallic", 0.0)}}
        return {"bsdf": {"type": "principled", "base_color": {"type": "rgb", "value": spec["albedo"]},
                         "roughness": spec.get("roughness", 0.5), "metallic": spec.get("metallic", 0.0),
                         "specular": f0 / 0.08}}
    if kind == "emitter":
        m = spec["emission"]
        return {"bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}},
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [x / math.pi for x in m]}}}
    s, a = JENSEN_2001.get(spec.get("preset"), (None, None)) if spec.get("preset") else (None, None)
    s = spec.get("sigma_s_prime", s)
    a = spec.get("sigma_a", a)
    eta = spec.get("eta", 1.3)
    sigma_t = [si + ai for si, ai in zip(s, a)]
    albedo = [si / ti for si, ti in zip(s, sigma_t)]
    if diffuse_only:
        raise SystemExit("--diffuse-only: translucent materials are not diffuse; leave them out of the scene")
    # Mitsuba takes σt as an RGB in [0, 1] times `scale`: normalise by the largest channel.
    peak = max(sigma_t)
    return {"bsdf": {"type": "roughdielectric", "distribution": "ggx", "alpha": alpha,
                     "int_ior": eta, "ext_ior": 1.0},
            "interior": {"type": "homogeneous", "sigma_t": {"type": "rgb", "value": [t / peak for t in sigma_t]},
                         "albedo": {"type": "rgb", "value": albedo}, "scale": mm_per_unit * peak}}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help="a Fovea scene file (assets/scenes/*.json)")
    p.add_argument("out", help="output .exr (a .png and .json are written beside it)")
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--height", type=int, default=240)
    p.add_argument("--spp", type=int, default=1024, help="samples per pixel")
    p.add_argument("--variant", default="scalar_rgb", help="scalar_rgb, llvm_ad_rgb (libllvm19), cuda_ad_rgb")
    p.add_argument("--max-depth", type=int, default=4096, help="path length bound (SSS needs thousands)")
    p.add_argument("--integrator", choices=["volpath", "volpathmis"], default="volpath",
                   help="volpathmis: spectral MIS, far less colour noise in chromatic media")
    p.add_argument("--seed-offset", type=int, default=0,
                   help="first pass's seed: runs with offsets ≥ the other's passes are independent and can be averaged")
    p.add_argument("--diffuse-only", action="store_true", help="path tracer, no media (radiosity checks)")
    p.add_argument("--drop-material", action="append", default=[], help="leave out objects of this material")
    p.add_argument("--passes", type=int, default=1, help="split the samples into passes (progress, memory)")
    p.add_argument("--surfaces", choices=["fovea", "principled"], default="fovea",
                   help="opaque surface model: Fovea's own (Lambert + GGX, tools/mitsuba_fovea_surface.py) "
                        "so that only light transport differs, or Disney's principled")
    p.add_argument("--split", action="store_true",
                   help="also write OUT-a.png and OUT-b.png from the even and the odd passes (the noise floor)")
    p.add_argument("--sun-half-angle-deg", type=float, default=10.0,
                   help="angular radius of the disc standing in for the directional light; 0: a "
                        "directional emitter as Fovea's (needs rough, not smooth, translucent boundaries)")
    a = p.parse_args()

    import mitsuba as mi
    mi.set_variant(a.variant)
    if a.surfaces == "fovea":
        import sys
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from mitsuba_fovea_surface import register
        register()
    scene_dir = os.path.dirname(os.path.abspath(a.scene))
    # Built-in meshes (bunny.ply) live in the repository's assets/meshes, wherever the scene is.
    mesh_dir = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "assets", "meshes")
    with open(a.scene) as f:
        s = json.load(f)
    mm = s.get("mm_per_unit", 10.0)
    light = s["light"]
    to_light = np.array(light["to_light"], dtype=float)
    to_light /= np.linalg.norm(to_light)
    e_light = [c * light["intensity"] for c in light["color"]]
    cam = s["camera"]
    d = {
        "type": "scene",
        "integrator": {"type": "path" if a.diffuse_only else a.integrator, "max_depth": a.max_depth,
                       "rr_depth": a.max_depth},
        "sensor": {
            "type": "perspective", "fov": cam["fov_y_deg"], "fov_axis": "y",
            "near_clip": cam["near"], "far_clip": cam["far"],
            "to_world": mi.ScalarTransform4f.look_at(origin=cam["eye"], target=cam["target"],
                                                     up=cam.get("up", [0, 1, 0])),
            "film": {"type": "hdrfilm", "width": a.width, "height": a.height, "pixel_format": "rgba",
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": max(1, a.spp // a.passes)},
        },
    }
    if light["intensity"] > 0 and a.sun_half_angle_deg == 0:
        # Fovea's own light: a directional emitter. Through a rough dielectric boundary the
        # path tracer reaches it by next-event estimation at the boundary (its lobe is not a
        # delta), and no sampled direction can hit it, so no fireflies from hitting a disc.
        d["sun"] = {"type": "directional", "direction": (-to_light).tolist(),
                    "irradiance": {"type": "rgb", "value": e_light}}
    elif light["intensity"] > 0:
        # A delta light cannot be reached through a smooth dielectric (next-event estimation
        # stops at the specular boundary), so the sun is a distant disc of small angular radius
        # α with radiance E / (π sin²α): the same irradiance, seen through the boundary.
        alpha = math.radians(a.sun_half_angle_deg)
        dist = 1000.0 * max(cam["far"], 1.0)
        radiance = [e / (math.pi * math.sin(alpha) ** 2) for e in e_light]
        centre = to_light * dist
        d["sun"] = {"type": "disk",
                    "to_world": mi.ScalarTransform4f.look_at(origin=centre.tolist(), target=[0, 0, 0],
                                                             up=[0, 1, 0] if abs(to_light[1]) < 0.99 else [1, 0, 0])
                    @ mi.ScalarTransform4f.scale(dist * math.tan(alpha)),
                    "emitter": {"type": "area", "radiance": {"type": "rgb", "value": radiance}}}
    ambient = s.get("ambient", 0.0)
    env = [ambient * c / math.pi for c in e_light]
    if ambient > 0:
        d["ambient"] = {"type": "constant", "radiance": {"type": "rgb", "value": env}}
    for i, o in enumerate(s["objects"]):
        if o["material"] in a.drop_material:
            continue
        m = material_dict(s["materials"][o["material"]], mm, a.diffuse_only, a.surfaces)
        if o["mesh"] == "quad":
            shape = {"type": "rectangle", "to_world": quad_transform(mi, o["corners"])}
        elif o["mesh"] == "plane":
            shape = {"type": "rectangle", "to_world": object_transform(mi, o)
                     @ mi.ScalarTransform4f.rotate([1, 0, 0], -90) @ mi.ScalarTransform4f.scale(0.5)}
        else:
            shape = {"type": "ply", "filename": os.path.join(mesh_dir, o["mesh"]), "to_world": object_transform(mi, o)}
        shape.update(m)
        d[f"object{i}"] = shape
    scene = mi.load_dict(d)
    halves = [None, None]
    for k in range(a.passes):
        img = np.array(mi.render(scene, seed=a.seed_offset + k), dtype=np.float64)
        halves[k % 2] = img if halves[k % 2] is None else halves[k % 2] + img
        print(f"pass {k + 1}/{a.passes}", flush=True)
    img = sum(h for h in halves if h is not None) / a.passes
    rgb = img[..., :3]
    # Coverage: pixels whose camera rays hit a surface (depth AOV > 0; edge pixels count as hit).
    d["integrator"] = {"type": "aov", "aovs": "dd:depth"}
    d["sensor"]["sampler"] = {"type": "independent", "sample_count": 64}
    d["sensor"]["film"].pop("pixel_format", None)
    d.pop("sun", None)
    for k in list(d):
        if k.startswith("object"):
            d[k].pop("emitter", None)
    depth = np.array(mi.render(mi.load_dict(d)), dtype=np.float64)
    alpha = (depth[..., -1:] > 0).astype(float)
    bg = np.array([srgb_decode(c) for c in s["background_srgb"]])

    def display(rgb):
        # Fovea's units are radiance × π; where rays leave the scene, Fovea's background shows.
        return rgb * math.pi - (1 - alpha) * np.array(env) * math.pi + (1 - alpha) * bg

    out = display(rgb)
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    mi.Bitmap(out.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(a.out)
    png = os.path.splitext(a.out)[0] + ".png"
    from PIL import Image
    Image.fromarray(np.round(srgb_encode(out) * 255).astype(np.uint8)).save(png)
    if a.split and a.passes >= 2:
        # The even and the odd passes alone: two independent renders at half the samples,
        # whose difference is the reference's own noise (its FLIP is the floor a perfect
        # renderer would score against one of them).
        for name, h, n in (("a", halves[0], (a.passes + 1) // 2), ("b", halves[1], a.passes // 2)):
            half = display(h[..., :3] / n)
            Image.fromarray(np.round(srgb_encode(half) * 255).astype(np.uint8)).save(
                os.path.splitext(a.out)[0] + f"-{name}.png")
    with open(os.path.splitext(a.out)[0] + ".json", "w") as f:
        json.dump({"scene": a.scene, "width": a.width, "height": a.height, "spp": a.spp,
                   "variant": a.variant, "surfaces": a.surfaces, "sun_half_angle_deg": a.sun_half_angle_deg,
                   "passes": a.passes, "max_depth": a.max_depth, "integrator": a.integrator,
                   "seed_offset": a.seed_offset,
                   "diffuse_only": a.diffuse_only,
                   "dropped": a.drop_material}, f, indent=2)
    print(f"wrote {a.out} and {png}")


if __name__ == "__main__":
    main()
