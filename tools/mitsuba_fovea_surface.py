"""Fovea's opaque surface model as a Mitsuba 3 BSDF, for tools/mitsuba_reference.py.

Why: the ground truth should differ from Fovea only where Fovea approximates light transport
(shadow maps, no interreflection, the dipole), not by a different choice of surface model.
Disney's `principled` adds retro-reflection and does not take the lobe's share out of the
diffuse part (+24% on a rough floor against Fovea); `roughplastic` compresses the diffuse
light inside its coating by 1/η² (−34%). This is the model of src/optics/specular.rs and
shaders/common.wgsl (`surface_light`), in Mitsuba's units (BRDF values, not ×π):

    f(l, v) = diffuse · (1 − E(n·l)) · (1 − E(n·v)) / π + D(h) · V(l, v) · F(v·h)

with GGX D, height-correlated Smith V, Schlick F with F90 = min(50 F0, 1), and E(μ) the lobe's
directional albedo, tabulated at 16 values of μ as F0·A(μ) + F90·B(μ) exactly as Fovea does.
Sampling: the GGX normal distribution (D·n·h) with probability `spec_prob`, else the cosine
hemisphere; the pdf is the mixture's, so the estimate is unbiased whichever is drawn.
"""
import math

import numpy as np

ALBEDO_TABLE = 16  # optics::specular::ALBEDO_TABLE
MIN_ALPHA = 0.002  # optics::specular::MIN_ALPHA


def smith_visibility(n_v, n_l, alpha):
    a2 = alpha * alpha
    v, l = np.clip(n_v, 1e-4, 1.0), np.clip(n_l, 1e-4, 1.0)
    return 0.5 / (l * np.sqrt(v * v * (1 - a2) + a2) + v * np.sqrt(l * l * (1 - a2) + a2))


def split_albedo(mu, alpha, n=96):
    """(A, B) of E(μ) = F0·A + F90·B: optics::specular::split_albedo, the same strata."""
    v = np.array([math.sqrt(max(1 - mu * mu, 0.0)), 0.0, mu])
    a2 = alpha * alpha
    u1, u2 = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n, indexing="ij")
    cos_t = np.sqrt((1 - u1) / (1 + (a2 - 1) * u1))
    sin_t = np.sqrt(np.maximum(1 - cos_t * cos_t, 0))
    phi = 2 * math.pi * u2
    h = np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], -1)
    v_h = h @ v
    n_l = 2 * v_h * h[..., 2] - v[2]
    ok = (n_l > 0) & (v_h > 0)
    w = np.where(ok, smith_visibility(mu, n_l, alpha) * 4 * n_l * v_h / cos_t, 0.0)
    fc = np.clip(1 - v_h, 0, 1) ** 5
    return float(((1 - fc) * w).sum() / (n * n)), float((fc * w).sum() / (n * n))


def albedo_table(alpha):
    mus = [max(i / (ALBEDO_TABLE - 1), 1e-3) for i in range(ALBEDO_TABLE)]
    return [split_albedo(mu, alpha) for mu in mus]


def register():
    """Registers the `fovea_surface` BSDF (after mi.set_variant)."""
    import drjit as dr
    import mitsuba as mi

    class FoveaSurface(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            base = [props["r"], props["g"], props["b"]]
            metallic = props.get("metallic", 0.0)
            f0_dielectric = props.get("f0", 0.04)
            self.alpha = max(props.get("alpha", 0.25), MIN_ALPHA)
            self.diffuse = mi.Color3f([c * (1 - metallic) for c in base])
            f0 = [f0_dielectric * (1 - metallic) + c * metallic for c in base]
            self.f0 = mi.Color3f(f0)
            self.f90 = mi.Color3f([min(50 * c, 1.0) for c in f0])
            table = albedo_table(self.alpha)
            self.table_a = mi.Float([t[0] for t in table])
            self.table_b = mi.Float([t[1] for t in table])
            # Draw the lobe about as often as it carries light (at least a quarter).
            self.spec_prob = 0.5 if max(f0) > 0.2 or self.alpha < 0.3 else 0.25
            self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide,
                                 mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = self.m_components[0] | self.m_components[1]

        def lobe_albedo(self, mu):
            x = dr.clip(mu, 0.0, 1.0) * (ALBEDO_TABLE - 1)
            i = dr.minimum(mi.UInt32(dr.floor(x)), ALBEDO_TABLE - 2)
            t = x - mi.Float(i)
            a = dr.lerp(dr.gather(mi.Float, self.table_a, i), dr.gather(mi.Float, self.table_a, i + 1), t)
            b = dr.lerp(dr.gather(mi.Float, self.table_b, i), dr.gather(mi.Float, self.table_b, i + 1), t)
            return dr.clip(self.f0 * a + self.f90 * b, 0.0, 1.0)

        def d(self, n_h):
            a2 = self.alpha * self.alpha
            c = dr.clip(n_h, 0.0, 1.0)
            k = c * c * (a2 - 1.0) + 1.0
            return a2 / (dr.pi * k * k)

        def brdf_cos(self, wi, wo):
            """f·cos θ_o, zero below either horizon."""
            n_v, n_l = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
            h = dr.normalize(wi + wo)
            a2 = self.alpha * self.alpha
            cv, cl = dr.clip(n_v, 1e-4, 1.0), dr.clip(n_l, 1e-4, 1.0)
            vis = 0.5 / (cl * dr.sqrt(cv * cv * (1 - a2) + a2) + cv * dr.sqrt(cl * cl * (1 - a2) + a2))
            fc = dr.power(1.0 - dr.clip(dr.dot(wi, h), 0.0, 1.0), 5.0)
            f = self.f0 + (self.f90 - self.f0) * fc
            cross = (1.0 - self.lobe_albedo(n_l)) * (1.0 - self.lobe_albedo(n_v))
            value = (self.diffuse * cross / dr.pi + self.d(h.z) * vis * f) * n_l
            return dr.select((n_v > 0) & (n_l > 0), value, 0.0)

        def mixture_pdf(self, wi, wo):
            n_l = mi.Frame3f.cos_theta(wo)
            h = dr.normalize(wi + wo)
            v_h = dr.dot(wi, h)
            spec = self.d(h.z) * h.z / dr.maximum(4.0 * v_h, 1e-8)
            pdf = (1 - self.spec_prob) * n_l / dr.pi + self.spec_prob * dr.select(v_h > 0, spec, 0.0)
            return dr.select((mi.Frame3f.cos_theta(wi) > 0) & (n_l > 0), pdf, 0.0)

        def sample(self, ctx, si, sample1, sample2, active):
            wi = si.wi
            # The lobe: h from D(h)·(n·h), cos²θ = (1 − u)/(1 + (α² − 1)u); l = reflect(v, h).
            a2 = self.alpha * self.alpha
            u = sample2.x
            cos_t = dr.sqrt((1 - u) / (1 + (a2 - 1) * u))
            sin_t = dr.sqrt(dr.maximum(1 - cos_t * cos_t, 0.0))
            phi = 2 * dr.pi * sample2.y
            h = mi.Vector3f(sin_t * dr.cos(phi), sin_t * dr.sin(phi), cos_t)
            spec_dir = 2.0 * dr.dot(wi, h) * h - wi
            diff_dir = mi.warp.square_to_cosine_hemisphere(sample2)
            pick_spec = sample1 < self.spec_prob
            wo = dr.select(pick_spec, spec_dir, diff_dir)
            bs = mi.BSDFSample3f()
            bs.wo = wo
            bs.pdf = self.mixture_pdf(wi, wo)
            bs.eta = 1.0
            bs.sampled_type = dr.select(pick_spec, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                        mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
            bs.sampled_component = dr.select(pick_spec, mi.UInt32(1), mi.UInt32(0))
            ok = active & (bs.pdf > 0) & (mi.Frame3f.cos_theta(wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)
            weight = self.brdf_cos(wi, wo) / dr.maximum(bs.pdf, 1e-8)
            return bs, dr.select(ok, weight, 0.0)

        def eval(self, ctx, si, wo, active):
            return dr.select(active, self.brdf_cos(si.wi, wo), 0.0)

        def pdf(self, ctx, si, wo, active):
            return dr.select(active, self.mixture_pdf(si.wi, wo), 0.0)

        def eval_pdf(self, ctx, si, wo, active):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def traverse(self, callback):
            pass

        def to_string(self):
            return f"FoveaSurface[alpha={self.alpha}]"

    mi.register_bsdf("fovea_surface", lambda props: FoveaSurface(props))
