#!/usr/bin/env python3
"""Render proofs of the lustre Mitsuba plugin (issue 33 §2), in llvm_ad_spectral.

1. GGX plate: Mitsuba through the plugin (`{"type": "lustre", "model": "ggx"}`) against
   Mitsuba's own `roughconductor` on the same plate, metal table and light. The two differ
   by the Smith G2 only: lustre's height-correlated 1/(1 + Λi + Λo) against Mitsuba's
   separable 1/((1 + Λi)(1 + Λo)). The expected ratio ρ of every pixel is computed from
   those closed forms, averaged over the light's solid angle as the pixel sees it; the
   residual plugin − ρ·roughconductor is compared, per brightness region, with the noise
   measured from the scatter of independent seeds of both renders.
2. Full-GHS plate: Mitsuba through the plugin against lustre's own renderer
   (`lustre.render`, the code path of `lustre render`) on the same scene, after Mitsuba's
   luminance constant (its film divides by 106.7503 nm, its ȳ integrates to 106.857 nm:
   `mitsuba_plate.y_normalisation_fix`, applied to the uniform emitter); the residual is
   compared with the seeds' scatter in the same way.

A region passes when |z| < 4, z = (mean residual) / (its standard error from the seeds).

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        python3 benches/peer/plugin_plates.py [--res 128] [--spp 64] [--seeds 2]

Needs `mitsuba==3.9.1` and the `lustre` package (`pip install ./python`) in the same Python.
Prints its tables and exits non-zero if a region fails. Nothing is written to disk.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import mitsuba_plate as mp  # noqa: E402

GGX_SCENES = ["ggx_cu_45deg", "ggx_cu_grazing"]
GHS_MATERIAL = {"model": "ghs", "sigma_um": 0.138, "lc_um": 2.0, "gamma": 2.0, "metal": "cu"}
GHS_SCENES = ["ggx_cu_45deg", "ggx_cu_normal"]  # their geometry, with the full-GHS material
Z_LIMIT = 4.0
REGIONS = 5
LIGHT_POINTS = 256


def luminance(img: np.ndarray) -> np.ndarray:
    return img @ np.array([0.2126, 0.7152, 0.0722])


def ggx_lambda(cos_t: np.ndarray, alpha: float) -> np.ndarray:
    """Smith Λ of GGX: (√(1 + α² tan²θ) − 1)/2."""
    c2 = np.clip(cos_t, 1e-12, 1.0) ** 2
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * (1.0 - c2) / c2) - 1.0)


def plate_points(mi, scene, res: int) -> tuple[np.ndarray, np.ndarray]:
    """Where each pixel centre's camera ray meets the scene: (points (N, 3), hit mask)."""
    sensor = scene.sensors()[0]
    y, x = np.mgrid[0:res, 0:res]
    pos = mi.Point2f(mi.Float(((x + 0.5) / res).ravel()), mi.Float(((y + 0.5) / res).ravel()))
    n = res * res
    ray, _ = sensor.sample_ray(mi.Float(np.zeros(n)), mi.Float(np.full(n, 0.5)), pos,
                               mi.Point2f(mi.Float(np.full(n, 0.5)), mi.Float(np.full(n, 0.5))))
    si = scene.ray_intersect(ray)
    p = np.asarray(si.p, dtype=np.float64).reshape(3, -1).T
    return p, np.asarray(si.is_valid(), dtype=bool)


def expected_g2_ratio(sc: dict, points: np.ndarray, alpha: float) -> np.ndarray:
    """Per pixel: ∫ f_hc cos dω / ∫ f_sep cos dω over the light sphere as the plate point
    sees it (uniform in the cone it subtends), with f_sep = f_hc · G2_sep / G2_hc; f_hc is
    lustre's GGX (Fresnel at 550 nm; it nearly cancels). Plate normal +y."""
    import lustre

    m = lustre.Material(model="ggx", alpha=alpha, metal="cu")
    cam = np.array(sc["camera"]["look_from"], dtype=np.float64)
    light = sc["lights"][0]
    c, r = np.array(light["center"], dtype=np.float64), float(light["radius"])
    rng = np.random.default_rng(5)
    u = rng.random((LIGHT_POINTS, 2))
    rho = np.ones(len(points))
    for i0 in range(0, len(points), 2048):
        p = points[i0:i0 + 2048]
        wi = cam - p
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        axis = c - p
        dist = np.linalg.norm(axis, axis=1, keepdims=True)
        axis /= dist
        cos_max = np.sqrt(1.0 - (r / dist[:, 0]) ** 2)
        # A frame around each axis, then directions uniform in the cone.
        t = np.cross(axis, [1.0, 0.0, 0.0])
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        b = np.cross(axis, t)
        ct = 1.0 - u[:, 0][None, :] * (1.0 - cos_max[:, None])
        st = np.sqrt(np.maximum(1.0 - ct * ct, 0.0))
        ph = 2.0 * math.pi * u[:, 1][None, :]
        wo = (ct[..., None] * axis[:, None, :] + (st * np.cos(ph))[..., None] * t[:, None, :]
              + (st * np.sin(ph))[..., None] * b[:, None, :])
        k = len(p)
        wi_l = np.repeat(wi[:, [0, 2, 1]], LIGHT_POINTS, axis=0)  # local frame: normal → z
        wo_l = wo.reshape(-1, 3)[:, [0, 2, 1]]
        f, _ = m.eval(wi_l, wo_l, 550.0)
        li, lo = ggx_lambda(wi_l[:, 2], alpha), ggx_lambda(wo_l[:, 2], alpha)
        sep_over_hc = (1.0 + li + lo) / ((1.0 + li) * (1.0 + lo))
        w = (f * np.maximum(wo_l[:, 2], 0.0)).reshape(k, LIGHT_POINTS)
        num, den = w.sum(axis=1), (w * sep_over_hc.reshape(k, LIGHT_POINTS)).sum(axis=1)
        rho[i0:i0 + 2048] = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
    return rho


def render_mitsuba(mi, dr, d: dict, spp: int, seeds: list[int]) -> tuple[np.ndarray, float]:
    scene = mi.load_dict(d)
    t0 = time.perf_counter()
    imgs = []
    for s in seeds:
        img = mi.render(scene, spp=spp, seed=s)
        dr.eval(img)
        imgs.append(np.array(img, dtype=np.float64)[..., :3])
    return np.stack(imgs), time.perf_counter() - t0


def render_lustre(sc: dict, res: int, spp: int, seeds: list[int]) -> tuple[np.ndarray, float]:
    import lustre

    scene = {k: v for k, v in sc.items() if k in ("camera", "integrator", "materials", "shapes", "lights")}
    scene["camera"] = {**scene["camera"], "resolution": [res, res]}
    scene["integrator"] = {**scene["integrator"], "sampler": "independent"}
    t0 = time.perf_counter()
    imgs = []
    for s in seeds:
        scene["film"] = {"spp": spp, "seed": s}
        imgs.append(np.asarray(lustre.render(scene), dtype=np.float64))
    return np.stack(imgs), time.perf_counter() - t0


def compare(label: str, a: np.ndarray, b: np.ndarray, rho: np.ndarray | None, mask: np.ndarray,
            check: bool = True) -> bool:
    """Residual b − ρ·a per brightness region (luminance quantiles of the lit pixels of a),
    against its standard error from the seeds' scatter; both stacks are (seeds, H, W, 3)."""
    h, w = a.shape[1:3]
    rho = np.ones((h, w)) if rho is None else rho.reshape(h, w)
    mask = mask.reshape(h, w)
    ya, yb = luminance(a), luminance(b)  # (seeds, H, W)
    ma, mb = ya.mean(0), yb.mean(0)
    va, vb = ya.var(0, ddof=1) / len(a), yb.var(0, ddof=1) / len(b)
    lit = mask & (ma > 1e-3 * ma.max())
    edges = np.quantile(ma[lit], np.linspace(0.0, 1.0, REGIONS + 1))
    print(f"\n{label}: {int(lit.sum())} lit pixels; luminance regions by quantile of the reference")
    print("  region   Y range             pixels   b/a raw    ρ (expected)  residual / ρa       z")
    ok = True
    for i in range(REGIONS):
        sel = lit & (ma >= edges[i]) & ((ma < edges[i + 1]) if i < REGIONS - 1 else (ma <= edges[i + 1]))
        ok &= report_region(f"  {i + 1}/{REGIONS}", edges[i], edges[i + 1], sel, ma, mb, va, vb, rho, check)
    ok &= report_region("  all lit", edges[0], edges[-1], lit, ma, mb, va, vb, rho, check)
    for ch, name in enumerate("RGB"):
        ca, cb = a[..., ch], b[..., ch]
        ok &= report_region(f"  all {name}  ", edges[0], edges[-1], lit, ca.mean(0), cb.mean(0),
                            ca.var(0, ddof=1) / len(a), cb.var(0, ddof=1) / len(b), rho, check)
    return ok


def report_region(name, lo, hi, sel, ma, mb, va, vb, rho, check) -> bool:
    n = int(sel.sum())
    sa, sb, sra = ma[sel].sum(), mb[sel].sum(), (rho * ma)[sel].sum()
    se = math.sqrt((vb[sel] + rho[sel] ** 2 * va[sel]).sum())
    z = (sb - sra) / se if se > 0 else float("inf")
    good = abs(z) < Z_LIMIT
    print(f"{name:9s} {lo:8.4f}–{hi:8.4f}  {n:7d}   {sb / sa:.5f}   {sra / sa:.5f}      "
          f"{(sb - sra) / sra:+.5f} ± {se / sra:.5f}  {z:+6.2f} {('ok' if good else 'FAIL') if check else ''}")
    return good


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--only", choices=["ggx", "ghs"])
    args = ap.parse_args()
    if args.seeds < 2:
        ap.error("--seeds must be ≥ 2 (the noise is measured from their scatter)")
    mp.set_llvm_path()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_spectral")
    import lustre.mitsuba

    lustre.mitsuba.register()
    scenes = {s["name"]: s for s in mp.load_scenes(HERE / "plate_scenes.toml")}
    print(f"mitsuba {mi.__version__}, llvm_ad_spectral, {args.res}×{args.res}, {args.spp} spp × "
          f"{args.seeds} seeds per renderer, {dr.thread_count()} threads, "
          f"load average {os.getloadavg()[0]:.1f}; luminance fix {mp.y_normalisation_fix(mi):.5f}"
          f" (106.7503 / 106.857 nm)")
    ok = True
    seeds = list(range(1, args.seeds + 1))
    y_fix = mp.y_normalisation_fix(mi)
    if args.only in (None, "ggx"):
        for name in GGX_SCENES:
            sc = scenes[name]
            alpha = float(sc["materials"]["plate"]["alpha"])
            d = mp.mitsuba_scene_dict(mi, sc, args.spp, resolution=[args.res, args.res])
            a, ta = render_mitsuba(mi, dr, d, args.spp, seeds)
            d["shape0"]["bsdf"] = {"type": "lustre", "model": "ggx", "alpha": alpha, "metal": "cu"}
            b, tb = render_mitsuba(mi, dr, d, args.spp, [s + 100 for s in seeds])
            points, hit = plate_points(mi, mi.load_dict(d), args.res)
            rho = expected_g2_ratio(sc, points, alpha)
            print(f"\n[{name}] roughconductor {ta:.1f} s, plugin {tb:.1f} s (wall); "
                  f"ρ = G2 ratio over the lit pixels {rho[hit].min():.5f}–{rho[hit].max():.5f}")
            ok &= compare(f"{name}: plugin (GGX, height-correlated G2) vs roughconductor × ρ", a, b, rho, hit)
            compare(f"{name}: the same without ρ (the G2 difference left in; not a check)", a, b, None, hit,
                    check=False)
    if args.only in (None, "ghs"):
        for base in GHS_SCENES:
            sc = dict(scenes[base])
            sc["materials"] = {"plate": dict(GHS_MATERIAL)}
            d = mp.mitsuba_scene_dict(mi, {**sc, "materials": {"plate": {"model": "ggx", "alpha": 0.2, "metal": "cu"}}},
                                      args.spp, resolution=[args.res, args.res])
            d["shape0"]["bsdf"] = {"type": "lustre", **GHS_MATERIAL}
            b, tb = render_mitsuba(mi, dr, d, args.spp, seeds)
            a, ta = render_lustre(sc, args.res, args.spp, seeds)
            _, hit = plate_points(mi, mi.load_dict(d), args.res)
            label = base.replace("ggx", "ghs")
            print(f"\n[{label}] full GHS σ 0.138 µm, Lc 2 µm, γ 2, Cu: lustre {ta:.1f} s, "
                  f"Mitsuba plugin {tb:.1f} s (wall)")
            ok &= compare(f"{label}: Mitsuba plugin vs lustre render", a, b, None, hit)
            # Without the luminance constant's fix the emitter, and so (direct light only)
            # every pixel, is 1/y_fix brighter: shows the check resolves it.
            compare(f"{label}: the same without the luminance fix (×{1 / y_fix:.5f}; not a check)",
                    a, b / y_fix, None, hit, check=False)
    print("\nall regions within noise" if ok else "\nSOME REGION FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
