#!/usr/bin/env python3
"""Reference values of Mitsuba 3's `roughplastic` BSDF (GGX coat over a diffuse base).

Writes mitsuba_roughplastic.json beside this file: for several parameter sets
(alpha, int_ior, ext_ior = 1.0, diffuse_reflectance, nonlinear) and a grid of
directions, Mitsuba's `eval` (which includes cos(theta_o)) with both components,
with the glossy coat only (component 0) and the diffuse base only (component
1), and its `pdf`.

Directions: wi at azimuth 0, wo at azimuth phi_o, both with cosines on the
nodes j/63 of Mitsuba's 64-entry transmittance table (cos = j / 63, j given),
so that its linear interpolation of t(cos) is exact there and the comparison
tests the model, not the table's spacing.

Conventions (Mitsuba): local frame with normal +z, wi and wo pointing away
from the surface; distribution "ggx" with sample_visible = true (the pdf is
the visible-normal one); alpha as lustre's GGX alpha. The scalar_rgb variant
with a grey reflectance: every channel is equal and channel 0 is recorded.

Run:  python3 -m venv venv && venv/bin/pip install mitsuba==3.9.1
      venv/bin/python mitsuba_roughplastic.py
"""

import json
import math
import os

import mitsuba as mi

mi.set_variant("scalar_rgb")

HERE = os.path.dirname(os.path.abspath(__file__))

CASES = [
    # alpha, int_ior, reflectance, nonlinear
    (0.1, 1.49, 0.5, False),
    (0.3, 1.5, 0.8, True),
    (0.05, 2.0, 0.2, False),
    (0.6, 1.33, 0.9, False),
    (0.2, 1.49, 1.0, False),
]
NODES = [63, 56, 45, 32, 20, 10, 4]
PHI_DEG = [0.0, 60.0, 135.0, 180.0]


def direction(j, phi_deg):
    mu = j / 63.0
    s = math.sqrt(max(0.0, 1.0 - mu * mu))
    p = math.radians(phi_deg)
    return [s * math.cos(p), s * math.sin(p), mu]


def main():
    out = {
        "source": "Mitsuba %s, variant scalar_rgb, plugin roughplastic "
        "(distribution ggx, sample_visible true, ext_ior 1.0)" % mi.__version__,
        "script": "crates/brdf/tests/data/mitsuba_roughplastic.py",
        "fields": "wi, wo: local directions; f_cos_total/f_cos_coat/f_cos_base: "
        "eval (f times cos theta_o) with both components / component 0 / component 1; "
        "pdf: pdf with both components",
        "cases": [],
    }
    for alpha, int_ior, rho, nonlinear in CASES:
        bsdf = mi.load_dict(
            {
                "type": "roughplastic",
                "distribution": "ggx",
                "alpha": alpha,
                "int_ior": int_ior,
                "ext_ior": 1.0,
                "nonlinear": nonlinear,
                "diffuse_reflectance": {"type": "rgb", "value": [rho, rho, rho]},
            }
        )
        rows = []
        for ji in NODES:
            for jo in NODES:
                for phi in PHI_DEG:
                    wi = direction(ji, 0.0)
                    wo = direction(jo, phi)
                    si = mi.SurfaceInteraction3f()
                    si.wi = mi.Vector3f(wi)
                    si.uv = mi.Point2f(0.5, 0.5)
                    vals = {}
                    for name, comp in [("total", None), ("coat", 0), ("base", 1)]:
                        ctx = mi.BSDFContext()
                        if comp is not None:
                            ctx.component = comp
                        vals[name] = float(bsdf.eval(ctx, si, mi.Vector3f(wo))[0])
                    pdf = float(bsdf.pdf(mi.BSDFContext(), si, mi.Vector3f(wo)))
                    rows.append(
                        {
                            "wi": wi,
                            "wo": wo,
                            "f_cos_total": vals["total"],
                            "f_cos_coat": vals["coat"],
                            "f_cos_base": vals["base"],
                            "pdf": pdf,
                        }
                    )
        out["cases"].append(
            {
                "alpha": alpha,
                "int_ior": int_ior,
                "ext_ior": 1.0,
                "reflectance": rho,
                "nonlinear": nonlinear,
                "rows": rows,
            }
        )
    with open(os.path.join(HERE, "mitsuba_roughplastic.json"), "w") as f:
        json.dump(out, f, indent=None)
        f.write("\n")


if __name__ == "__main__":
    main()
