#!/usr/bin/env python3
"""Builds Fovea's shipped glTF scenes from the Stanford bunny and simple shapes.

Writes binary glTF (.glb) by hand (no dependencies), so the files exercise Fovea's real glTF
loader: a node hierarchy with rotations and scales, metallic-roughness materials, a base-colour
texture (a PNG embedded in the BIN chunk), KHR_materials_volume / transmission /
diffuse_transmission / ior for translucent media, KHR_lights_punctual (directional, point,
spot) and a perspective camera.

    python3 tools/make_scenes.py   # rewrites assets/scenes/gallery.glb and assets/models/*.glb

Units are metres (glTF's); light intensities are lux (directional) and candela (point, spot).
"""
import json
import math
import os
import struct
import zlib

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    head, body = data.split(b"end_header\n", 1)
    lines = head.decode().splitlines()
    nv = int(next(l for l in lines if l.startswith("element vertex")).split()[2])
    nf = int(next(l for l in lines if l.startswith("element face")).split()[2])
    pos = [struct.unpack_from("<3f", body, 12 * i) for i in range(nv)]
    off, idx = 12 * nv, []
    for _ in range(nf):
        n = body[off]
        idx.extend(struct.unpack_from("<%di" % n, body, off + 1)[:3])
        off += 1 + 4 * n
    return pos, idx


def png(width, height, pixel):
    """A truecolour PNG from pixel(x, y) -> (r, g, b) bytes."""
    raw = b"".join(
        b"\x00" + bytes(c for x in range(width) for c in pixel(x, y)) for y in range(height)
    )

    def chunk(kind, payload):
        c = struct.pack(">I", len(payload)) + kind + payload
        return c + struct.pack(">I", zlib.crc32(kind + payload) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9))
            + chunk(b"IEND", b""))


def quat_y(deg):
    a = math.radians(deg) / 2
    return [0.0, math.sin(a), 0.0, math.cos(a)]


def look_rotation(eye, target):
    """Quaternion turning glTF's camera/light -Z towards target (with +Y up)."""
    f = [t - e for t, e in zip(target, eye)]
    n = math.sqrt(sum(c * c for c in f))
    f = [c / n for c in f]
    yaw = math.atan2(-f[0], -f[2])
    pitch = math.asin(max(-1.0, min(1.0, f[1])))
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    # yaw about Y, then pitch about the local X
    return [cy * sp, sy * cp, -sy * sp, cy * cp]


class Glb:
    def __init__(self):
        self.bin = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "fovea tools/make_scenes.py"},
                    "buffers": [], "bufferViews": [], "accessors": [], "meshes": [],
                    "materials": [], "nodes": [], "scenes": [{"nodes": []}], "scene": 0}
        self.used = set()

    def view(self, data, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            v["target"] = target
        self.bin.extend(data)
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, values, kind, comp=5126):
        flat = [c for v in values for c in (v if isinstance(v, (list, tuple)) else [v])]
        fmt = "<%d%s" % (len(flat), "f" if comp == 5126 else "I")
        target = 34963 if comp == 5125 else 34962
        a = {"bufferView": self.view(struct.pack(fmt, *flat), target), "componentType": comp,
             "count": len(values), "type": kind}
        if kind == "VEC3":
            a["min"] = [min(v[i] for v in values) for i in range(3)]
            a["max"] = [max(v[i] for v in values) for i in range(3)]
        self.doc["accessors"].append(a)
        return len(self.doc["accessors"]) - 1

    def mesh(self, name, pos, idx, material, uv=None):
        attrs = {"POSITION": self.accessor(pos, "VEC3")}
        if uv:
            attrs["TEXCOORD_0"] = self.accessor(uv, "VEC2")
        prim = {"attributes": attrs, "indices": self.accessor(idx, "SCALAR", 5125),
                "material": material}
        self.doc["meshes"].append({"name": name, "primitives": [prim]})
        return len(self.doc["meshes"]) - 1

    def material(self, m, ext=None):
        if ext:
            m["extensions"] = ext
            self.used.update(ext)
        self.doc["materials"].append(m)
        return len(self.doc["materials"]) - 1

    def texture(self, png_bytes):
        self.doc.setdefault("images", []).append(
            {"bufferView": self.view(png_bytes), "mimeType": "image/png"})
        self.doc.setdefault("samplers", [{}])
        self.doc.setdefault("textures", []).append(
            {"source": len(self.doc["images"]) - 1, "sampler": 0})
        return len(self.doc["textures"]) - 1

    def node(self, n, root=True):
        if "light" in n:
            n["extensions"] = {"KHR_lights_punctual": {"light": n.pop("light")}}
        self.doc["nodes"].append(n)
        i = len(self.doc["nodes"]) - 1
        if root:
            self.doc["scenes"][0]["nodes"].append(i)
        return i

    def light(self, l):
        ext = self.doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {"lights": []})
        ext["lights"].append(l)
        self.used.add("KHR_lights_punctual")
        return len(ext["lights"]) - 1

    def write(self, path):
        self.doc["buffers"] = [{"byteLength": len(self.bin)}]
        if self.used:
            self.doc["extensionsUsed"] = sorted(self.used)
        js = json.dumps(self.doc, separators=(",", ":")).encode()
        js += b" " * (-len(js) % 4)
        binary = bytes(self.bin) + b"\x00" * (-len(self.bin) % 4)
        total = 12 + 8 + len(js) + 8 + len(binary)
        with open(path, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, total))
            f.write(struct.pack("<II", len(js), 0x4E4F534A) + js)
            f.write(struct.pack("<II", len(binary), 0x004E4942) + binary)
        print("wrote", os.path.relpath(path, ROOT), total, "bytes")


def floor(size, tiles, cells=1):
    """A square in XZ facing +Y, split into cells² quads."""
    h, pos, uv, idx = size / 2, [], [], []
    for j in range(cells + 1):
        for i in range(cells + 1):
            u, v = i / cells, j / cells
            pos.append((-h + size * u, 0.0, -h + size * v))
            uv.append((tiles * u, tiles * v))
    for j in range(cells):
        for i in range(cells):
            a = j * (cells + 1) + i
            b = a + cells + 1
            idx += [a, b, b + 1, a, b + 1, a + 1]
    return pos, idx, uv


def sphere(r, rings=24, segs=48):
    pos, idx, uv = [], [], []
    for i in range(rings + 1):
        t = math.pi * i / rings
        for j in range(segs + 1):
            p = 2 * math.pi * j / segs
            pos.append((r * math.sin(t) * math.cos(p), r * math.cos(t), -r * math.sin(t) * math.sin(p)))
            uv.append((j / segs, i / rings))
    for i in range(rings):
        for j in range(segs):
            a, b = i * (segs + 1) + j, (i + 1) * (segs + 1) + j
            idx += [a, b, a + 1, a + 1, b, b + 1]
    return pos, idx, uv


def checker(x, y):
    c = 200 if ((x // 16) + (y // 16)) % 2 == 0 else 120
    return (c, c - 10, c - 30)


def bevel(x, y):
    """Tangent-space normal of 16-texel tiles with gently sloped 2-texel edges (grout)."""
    u, v = x % 16, y % 16
    nx = -0.35 if u < 2 else (0.35 if u > 13 else 0.0)
    ny = -0.35 if v < 2 else (0.35 if v > 13 else 0.0)
    n = math.sqrt(nx * nx + ny * ny + 1.0)
    return tuple(int(round((c / n * 0.5 + 0.5) * 255)) for c in (nx, ny, 1.0))


def bunny_node(g, mesh, x, z, yaw, scale=1.0):
    return g.node({"mesh": mesh, "translation": [x, 0.0, z], "rotation": quat_y(yaw),
                   "scale": [scale] * 3})


def translucent(g, name, colour, distance, atten, ior=1.45, rough=0.35):
    return g.material(
        {"name": name, "pbrMetallicRoughness": {"baseColorFactor": colour + [1.0],
                                                "metallicFactor": 0.0, "roughnessFactor": rough}},
        {"KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 1.0},
         "KHR_materials_volume": {"thicknessFactor": 0.05, "attenuationDistance": distance,
                                  "attenuationColor": atten},
         "KHR_materials_ior": {"ior": ior}})


def gallery(bunny):
    """Textured floor, a marble bunny, a glossy metal sphere, key + spot + point lights."""
    g = Glb()
    tex = g.texture(png(128, 128, checker))
    bumps = g.texture(png(128, 128, bevel))
    floor_m = g.material({"name": "tiles", "normalTexture": {"index": bumps}, "pbrMetallicRoughness": {
        "baseColorTexture": {"index": tex}, "metallicFactor": 0.0, "roughnessFactor": 0.55}})
    marble = translucent(g, "marble", [0.92, 0.90, 0.86], 0.4, [0.8, 0.76, 0.72])
    metal = g.material({"name": "gold", "pbrMetallicRoughness": {
        "baseColorFactor": [1.0, 0.78, 0.34, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.25}})
    fp, fi, fu = floor(0.8, 6)
    g.node({"mesh": g.mesh("floor", fp, fi, floor_m, fu), "translation": [0, 0, 0]})
    bunny_node(g, g.mesh("bunny", bunny[0], bunny[1], marble), -0.03, 0.0, -15.0)
    sp, si, su = sphere(0.045)
    g.node({"mesh": g.mesh("sphere", sp, si, metal, su), "translation": [0.13, 0.045, 0.05]})
    key = g.light({"type": "directional", "name": "sun", "color": [1.0, 0.97, 0.92], "intensity": 3.0})
    g.node({"light": key, "rotation": look_rotation([0.6, 1.0, 0.35], [0, 0, 0])})
    spot = g.light({"type": "spot", "name": "rim", "color": [0.55, 0.7, 1.0], "intensity": 1.2,
                    "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.45}})
    g.node({"light": spot, "translation": [-0.25, 0.35, -0.35],
            "rotation": look_rotation([-0.25, 0.35, -0.35], [0, 0.06, 0])})
    warm = g.light({"type": "point", "name": "lamp", "color": [1.0, 0.6, 0.3], "intensity": 0.08,
                    "range": 1.5})
    g.node({"light": warm, "translation": [0.25, 0.18, 0.22]})
    g.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.05, "zfar": 5.0}}]
    g.node({"camera": 0, "translation": [0.05, 0.24, 0.55],
            "rotation": look_rotation([0.05, 0.24, 0.55], [0.03, 0.06, 0])})
    return g


def lamps(bunny):
    """A plaster bunny and a jade one under four coloured punctual lights of three kinds."""
    g = Glb()
    plaster = g.material({"name": "plaster", "pbrMetallicRoughness": {
        "baseColorFactor": [0.85, 0.84, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.7}})
    jade = translucent(g, "jade", [0.35, 0.75, 0.45], 0.05, [0.3, 0.8, 0.45], ior=1.6, rough=0.2)
    ground = g.material({"name": "slate", "pbrMetallicRoughness": {
        "baseColorFactor": [0.25, 0.26, 0.3, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.4}})
    fp, fi, _ = floor(0.9, 1)
    g.node({"mesh": g.mesh("ground", fp, fi, ground)})
    # A parent node turns and scales both bunnies together (exercises the hierarchy).
    group = g.node({"rotation": quat_y(10.0), "scale": [1.1, 1.1, 1.1], "children": []})
    b1 = g.node({"mesh": g.mesh("bunny-plaster", bunny[0], bunny[1], plaster),
                 "translation": [-0.09, 0.0, 0], "rotation": quat_y(20)}, root=False)
    b2 = g.node({"mesh": g.mesh("bunny-jade", bunny[0], bunny[1], jade),
                 "translation": [0.09, 0.0, 0], "rotation": quat_y(-20)}, root=False)
    g.doc["nodes"][group]["children"] = [b1, b2]
    key = g.light({"type": "directional", "name": "moon", "color": [0.7, 0.75, 1.0], "intensity": 0.6})
    g.node({"light": key, "rotation": look_rotation([-0.3, 1.0, 0.6], [0, 0, 0])})
    for name, colour, at, kind in [("red", [1.0, 0.25, 0.2], [-0.25, 0.2, 0.15], "point"),
                                   ("blue", [0.25, 0.4, 1.0], [0.25, 0.22, 0.1], "point"),
                                   ("amber", [1.0, 0.75, 0.3], [0.0, 0.45, 0.3], "spot"),
                                   ("teal", [0.3, 1.0, 0.85], [0.1, 0.3, -0.35], "spot")]:
        light = {"type": kind, "name": name, "color": colour, "intensity": 0.03 if kind == "point" else 0.1}
        node = {"translation": at}
        if kind == "spot":
            light["spot"] = {"innerConeAngle": 0.2, "outerConeAngle": 0.42}
            node["rotation"] = look_rotation(at, [0, 0.05, 0])
        node["light"] = g.light(light)
        g.node(node)
    g.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.05, "zfar": 5.0}}]
    g.node({"camera": 0, "translation": [0.0, 0.24, 0.52],
            "rotation": look_rotation([0.0, 0.24, 0.52], [0.0, 0.05, 0.0])})
    return g


# Jensen et al. 2001's measured media (σ's, σa per mm), as in src/scene/material.rs.
JENSEN = {"marble": ([2.19, 2.62, 3.00], [0.0021, 0.0041, 0.0071]),
          "skin1": ([0.74, 0.88, 1.01], [0.032, 0.17, 0.48]),
          "wholemilk": ([2.55, 3.21, 3.77], [0.0011, 0.0024, 0.014]),
          "ketchup": ([0.18, 0.07, 0.03], [0.061, 0.97, 1.45])}


def jensen_volume(sigma_s, sigma_a, eta=1.3):
    """glTF base colour and KHR_materials_volume attenuation that Fovea's mapping
    (docs/scenes.md, "glTF materials") turns back into exactly these coefficients: the base
    colour is the dipole's total diffuse reflectance (which fixes α' = σ's/σ't), and Beer's law
    over attenuationDistance gives σa. The distance is chosen so the darkest channel keeps 10⁻³."""
    fdr = -1.440 / eta ** 2 + 0.710 / eta + 0.668 + 0.0636 * eta
    a = (1 + fdr) / (1 - fdr)
    colour = []
    for ss, sa in zip(sigma_s, sigma_a):
        alpha = ss / (ss + sa)
        t = math.sqrt(3 * (1 - alpha))
        colour.append(0.5 * alpha * (1 + math.exp(-4 / 3 * a * t)) * math.exp(-t))
    distance_mm = math.log(1000.0) / max(sigma_a)
    attenuation = [math.exp(-sa * distance_mm) for sa in sigma_a]
    return colour, distance_mm / 1000.0, attenuation


def jensen_material(g, medium):
    """One of Jensen 2001's media as a glTF material Fovea maps back to its coefficients."""
    colour, distance, attenuation = jensen_volume(*JENSEN[medium])
    return g.material(
        {"name": medium, "pbrMetallicRoughness": {"baseColorFactor": colour + [1.0],
                                                  "metallicFactor": 0.0, "roughnessFactor": 0.3}},
        {"KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 1.0},
         "KHR_materials_volume": {"thicknessFactor": 0.05, "attenuationDistance": distance,
                                  "attenuationColor": attenuation},
         "KHR_materials_ior": {"ior": 1.3}})


def bunny_scene(bunny, medium, to_light, light_colour):
    """A built-in bunny scene as glTF: the bunny in `medium`, back-lit, its camera."""
    g = Glb()
    m = jensen_material(g, medium)
    g.node({"mesh": g.mesh("bunny", bunny[0], bunny[1], m)})
    key = g.light({"type": "directional", "name": "back light", "color": light_colour, "intensity": 2.5})
    g.node({"light": key, "rotation": look_rotation(to_light, [0, 0, 0])})
    camera(g, [0.0, 0.07, 0.24], [0.0, 0.046, 0.0], 32, 1.0)
    return g


def materials_scene(bunny):
    """The built-in `materials` scene as glTF: marble, skin, whole milk and ketchup bunnies
    beside a plaster one on a plaster floor, lit from behind and to the side (lengths in
    metres: the scene file's units are centimetres)."""
    g = Glb()
    plaster = g.material({"name": "plaster", "pbrMetallicRoughness": {
        "baseColorFactor": [0.75, 0.73, 0.70, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5}})
    for k, medium in enumerate(["marble", "skin1", "wholemilk", "ketchup", None]):
        m = plaster if medium is None else jensen_material(g, medium)
        mesh = g.mesh("bunny-" + (medium or "plaster"), bunny[0], bunny[1], m)
        g.node({"mesh": mesh, "translation": [-0.12 + 0.06 * k, 0.0, 0.0], "scale": [0.6] * 3})
    pos, idx, _ = floor(0.4, 1)
    g.node({"mesh": g.mesh("floor", pos, idx, plaster)})
    key = g.light({"type": "directional", "name": "key", "color": [1.0, 0.96, 0.9], "intensity": 1.0})
    g.node({"light": key, "rotation": look_rotation([0.55, 0.5, -0.67], [0, 0, 0])})
    camera(g, [0.0, 0.10, 0.38], [0.0, 0.03, 0.0], 36, 2.0)
    return g


def grid(corners, n):
    """A parallelogram as an n × n grid of triangles, counter-clockwise seen from its front
    (corners as in a scene file's quad): radiosity receives at mesh vertices, so a wall needs
    a lattice of them to show the lamp's falloff and the colour bleeding."""
    c0, c1, _, c3 = corners
    pos, idx = [], []
    for j in range(n + 1):
        for i in range(n + 1):
            pos.append(tuple(c0[k] + (c1[k] - c0[k]) * i / n + (c3[k] - c0[k]) * j / n
                             for k in range(3)))
    for j in range(n):
        for i in range(n):
            a, b = j * (n + 1) + i, (j + 1) * (n + 1) + i
            idx += [a, a + 1, b + 1, a, b + 1, b]
    return pos, idx


def opaque_material(g, name, albedo, rough=0.5):
    return g.material({"name": name, "pbrMetallicRoughness": {
        "baseColorFactor": albedo + [1.0], "metallicFactor": 0.0, "roughnessFactor": rough}})


def camera(g, eye, target, fov_deg, zfar):
    g.doc["cameras"] = [{"type": "perspective", "perspective": {
        "yfov": math.radians(fov_deg), "znear": 0.01, "zfar": zfar}}]
    g.node({"camera": 0, "translation": eye, "rotation": look_rotation(eye, target)})


def plaster_scene(bunny, with_floor):
    """The built-in `bunny` (a plaster bunny) or, with its floor, `opaque`, as glTF: the scene
    files' centimetres in metres, their key light as a directional light."""
    g = Glb()
    plaster = opaque_material(g, "plaster", [0.80, 0.76, 0.70])
    g.node({"mesh": g.mesh("bunny", bunny[0], bunny[1], plaster)})
    if with_floor:
        pos, idx, _ = floor(0.4, 1)
        g.node({"mesh": g.mesh("floor", pos, idx, opaque_material(g, "floor", [0.35, 0.36, 0.38]))})
    key = g.light({"type": "directional", "name": "key", "color": [1.0, 0.96, 0.9], "intensity": 1.0})
    g.node({"light": key, "rotation": look_rotation([-0.55, 0.75, 0.6], [0, 0, 0])})
    if with_floor:
        camera(g, [0.0, 0.09, 0.26], [0.0, 0.04, 0.0], 34, 1.0)
    else:
        camera(g, [0.0, 0.07, 0.24], [0.0, 0.046, 0.0], 32, 1.0)
    return g


def cornell_scene(bunny):
    """The built-in `cornell` as glTF: five walls as 24 × 24 grids, the lamp an emissive
    square (KHR_materials_emissive_strength: exitance 30), a marble bunny, no punctual light,
    so Fovea lights it by radiosity from the lamp alone."""
    g = Glb()
    s = 0.01  # the scene file's units are centimetres
    walls = [
        ("white", [[-10, 0, -10], [-10, 0, 10], [10, 0, 10], [10, 0, -10]]),
        ("white", [[-10, 20, -10], [10, 20, -10], [10, 20, 10], [-10, 20, 10]]),
        ("white", [[-10, 0, -10], [10, 0, -10], [10, 20, -10], [-10, 20, -10]]),
        ("red", [[-10, 0, -10], [-10, 20, -10], [-10, 20, 10], [-10, 0, 10]]),
        ("green", [[10, 0, -10], [10, 0, 10], [10, 20, 10], [10, 20, -10]]),
    ]
    colours = {"white": [0.73, 0.73, 0.71], "red": [0.63, 0.065, 0.05], "green": [0.14, 0.45, 0.091]}
    mats = {k: opaque_material(g, k, v) for k, v in colours.items()}
    for k, (m, corners) in enumerate(walls):
        pos, idx = grid([[c * s for c in p] for p in corners], 24)
        g.node({"mesh": g.mesh("wall-%d-%s" % (k, m), pos, idx, mats[m])})
    lamp = g.material({"name": "lamp", "emissiveFactor": [1.0, 0.95, 26.0 / 30.0],
                       "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}},
                      {"KHR_materials_emissive_strength": {"emissiveStrength": 30.0}})
    pos, idx = grid([[c * s for c in p] for p in
                     [[-3, 19.95, -3], [3, 19.95, -3], [3, 19.95, 3], [-3, 19.95, 3]]], 4)
    g.node({"mesh": g.mesh("lamp", pos, idx, lamp)})
    marble = jensen_material(g, "marble")
    g.node({"mesh": g.mesh("bunny", bunny[0], bunny[1], marble), "translation": [0.01, 0.0, -0.015],
            "rotation": quat_y(20), "scale": [0.85] * 3})
    camera(g, [0.0, 0.10, 0.48], [0.0, 0.095, 0.0], 32, 2.0)
    return g


if __name__ == "__main__":
    bunny = read_ply(os.path.join(ROOT, "assets", "meshes", "bunny.ply"))
    # The scan is ~9.7 units tall: make it a 15 cm bunny standing on y = 0, centred in x, z.
    xs, ys, zs = zip(*bunny[0])
    cx, cz, y0 = (min(xs) + max(xs)) / 2, (min(zs) + max(zs)) / 2, min(ys)
    k = 0.15 / (max(ys) - y0)
    bunny = ([((x - cx) * k, (y - y0) * k, (z - cz) * k) for x, y, z in bunny[0]], bunny[1])
    # The gallery is a built-in scene (the default); lamps is an example model to serve.
    gallery(bunny).write(os.path.join(ROOT, "assets", "scenes", "gallery.glb"))
    lamps(bunny).write(os.path.join(ROOT, "assets", "models", "lamps.glb"))
    # bunny-marble and bunny-skin as glTF (the scan at its own size: 9.7 cm, in metres).
    raw = read_ply(os.path.join(ROOT, "assets", "meshes", "bunny.ply"))
    cm = ([(x * 0.01, y * 0.01, z * 0.01) for x, y, z in raw[0]], raw[1])
    for medium, name in [("marble", "marble-bunny"), ("skin1", "skin-bunny")]:
        bunny_scene(cm, medium, [0.35, 0.45, -0.82], [1.0, 0.96, 0.9]).write(
            os.path.join(ROOT, "assets", "models", name + ".glb"))
    materials_scene(cm).write(os.path.join(ROOT, "assets", "models", "media-bunnies.glb"))
    models = os.path.join(ROOT, "assets", "models")
    plaster_scene(cm, False).write(os.path.join(models, "plaster-bunny.glb"))
    plaster_scene(cm, True).write(os.path.join(models, "plaster-bunny-floor.glb"))
    cornell_scene(cm).write(os.path.join(models, "cornell-box.glb"))
