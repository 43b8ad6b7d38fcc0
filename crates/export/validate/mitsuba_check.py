#!/usr/bin/env python3
"""Checks lustre's RGL exports with Mitsuba 3's own `measured` plugin.

  record   export small tables of a few materials with `lustre brdf export`, evaluate them
           with Mitsuba (eval, pdf, sample) at random directions and wavelengths, and write
           crates/export/validate/mitsuba_eval.json. crates/export/tests/mitsuba_recorded.rs
           rebuilds the same tables with the library and reads them with export::RglTable:
           the two readers must agree (no Python in `cargo test`).
  plate    render plates (the peer benchmark's geometry, benches/peer/plate_scenes.toml)
           with Mitsuba's `measured` plugin reading a default-resolution export, and with
           lustre rendering the model itself; write validate/plates.json and print the
           ratios of the two images (whole lit area and 32x32 blocks).

Run from the repository root with a Python that has mitsuba==3.9.1 and numpy (e.g.
/work/venvs/h33x/bin/python). `--lustre` names the lustre binary (default
target/release/lustre, else target/debug/lustre). See crates/export/README.md.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent.parent
sys.path.insert(0, str(REPO / "benches" / "peer"))

# Small tables (the Rust test rebuilds them in well under a second each); the options
# are RglOptions fields, the material a brdf::spec::MaterialDesc.
SMALL = {
    "theta_i_deg": [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0],
    "sample_nodes": 24,
    "vndf_nodes": [48, 24],
    "ndf_nodes": [96, 24],
    "sigma_nodes": [48, 24],
    "phi_i_nodes": 5,
    "wavelengths_nm": [400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0],
    "rgb": False,
    "drop_specular": False,
}

CASES = [
    {"name": "ggx_cu", "material": {"model": "ggx", "alpha": 0.2, "metal": "cu"}, "options": SMALL},
    {"name": "ghs_s280", "material": {"model": "ghs", "sigma_um": 0.28, "lc_um": 5.0, "gamma": 3.0,
                                      "metal": "brass"},
     "options": dict(SMALL, drop_specular=True)},
    {"name": "ggx_aniso_au_rgb", "material": {"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.3,
                                              "metal": "au"},
     "options": dict(SMALL, rgb=True)},
]


def lustre_binary(arg: str | None) -> Path:
    if arg:
        return Path(arg)
    for p in (REPO / "target" / "release" / "lustre", REPO / "target" / "debug" / "lustre"):
        if p.exists():
            return p
    sys.exit("no lustre binary: cargo build (or pass --lustre)")


def cli_args(material_file: Path, o: dict, out: Path) -> list[str]:
    a = [str(material_file), "-o", str(out), "--check-samples", "0",
         "--theta-i", ",".join(repr(t) for t in o["theta_i_deg"]),
         "--sample-nodes", str(o["sample_nodes"]),
         "--vndf-nodes", ",".join(map(str, o["vndf_nodes"])),
         "--ndf-nodes", ",".join(map(str, o["ndf_nodes"])),
         "--sigma-nodes", ",".join(map(str, o["sigma_nodes"])),
         "--phi-nodes", str(o["phi_i_nodes"]),
         "--wavelengths", ",".join(repr(w) for w in o["wavelengths_nm"])]
    if o["rgb"]:
        a.append("--rgb")
    if o["drop_specular"]:
        a.append("--drop-specular")
    return a


def toml_text(d: dict) -> str:
    return "".join(f"{k} = {json.dumps(v)}\n" for k, v in d.items())


def export(lustre: Path, material: dict, o: dict, tmp: Path, name: str) -> Path:
    mat = tmp / f"{name}.toml"
    mat.write_text(toml_text(material))
    out = tmp / f"{name}.bsdf"
    subprocess.run([str(lustre), "brdf", "export"] + cli_args(mat, o, out), check=True,
                   stdout=subprocess.DEVNULL)
    return out


def direction(theta: float, phi: float):
    return [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)]


def record(args) -> None:
    import mitsuba as mi
    import numpy as np

    lustre = lustre_binary(args.lustre)
    rng = np.random.default_rng(20261206)
    cases = []
    with tempfile.TemporaryDirectory() as tmp:
        for case in CASES:
            o = case["options"]
            path = export(lustre, case["material"], o, Path(tmp), case["name"])
            mi.set_variant("scalar_rgb" if o["rgb"] else "scalar_spectral")
            bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
            ctx = mi.BSDFContext()
            rows, samples = [], []
            for _ in range(args.rows):
                # wi over the whole hemisphere; wo near the mirror direction half of the time.
                ti, pi_ = math.acos(rng.uniform(0.02, 1.0)), rng.uniform(-math.pi, math.pi)
                if rng.uniform() < 0.5:
                    to, po = ti + rng.normal(0.0, 0.15), pi_ + math.pi + rng.normal(0.0, 0.2)
                    to = min(abs(to), 1.5)
                else:
                    to, po = math.acos(rng.uniform(0.02, 1.0)), rng.uniform(-math.pi, math.pi)
                wi, wo = direction(ti, pi_), direction(to, po)
                si = mi.SurfaceInteraction3f()
                si.wi = mi.Vector3f(wi)
                if o["rgb"]:
                    lams = [0.0, 1.0, 2.0]
                else:
                    lams = sorted(float(x) for x in rng.uniform(380.0, 720.0, 4))
                    si.wavelengths = mi.Spectrum(lams)
                val = bsdf.eval(ctx, si, mi.Vector3f(wo))
                pdf = bsdf.pdf(ctx, si, mi.Vector3f(wo))
                rows.append({"wi": wi, "wo": wo, "lambda": lams,
                             "f_cos": [float(val[k]) for k in range(3 if o["rgb"] else 4)],
                             "pdf": float(pdf)})
                u = [float(x) for x in rng.uniform(0.0, 1.0, 2)]
                bs, w = bsdf.sample(ctx, si, 0.5, mi.Point2f(u))
                samples.append({"wi": wi, "u": u, "wo": [float(bs.wo[k]) for k in range(3)],
                                "pdf": float(bs.pdf)})
            cases.append(dict(case, mitsuba_variant=mi.variant(), rows=rows, samples=samples))
            print(f"{case['name']}: {len(rows)} evaluations, {len(samples)} samples")
    out = HERE / "mitsuba_eval.json"
    doc = {"generator": "crates/export/validate/mitsuba_check.py record",
           "mitsuba": mi.__version__,
           "note": "f_cos is Mitsuba's BSDF::eval (f times cos theta_o); lambda in nm, or the "
                   "channel 0, 1, 2 of an RGB file; sample() got sample2 = u",
           "cases": cases}
    tmp = out.with_name(f".{out.name}.tmp")
    tmp.write_text(json.dumps(doc, indent=1) + "\n")
    os.replace(tmp, out)
    print(f"wrote {out}")


# ---------------------------------------------------------------------------------------
# Plates

S280_GHS = {"model": "ghs", "sigma_um": 0.28, "lc_um": 5.0, "gamma": 3.0, "metal": "brass"}
PLATES = [
    # (name, scene of plate_scenes.toml, material keys for lustre, export flags)
    ("ggx_cu_45deg", "ggx_cu_45deg", {"model": "ggx", "alpha": 0.2, "metal": "cu"}, []),
    ("ggx_cu_grazing", "ggx_cu_grazing", {"model": "ggx", "alpha": 0.2, "metal": "cu"}, []),
    ("ghs_s280_normal", "ggx_cu_normal", S280_GHS, ["--drop-specular"]),
    ("ghs_s280_45deg", "ggx_cu_45deg", S280_GHS, ["--drop-specular"]),
    # At 80° the coherent lobe the table leaves out reflects the light itself.
    ("ghs_s280_grazing", "ggx_cu_grazing", S280_GHS, ["--drop-specular"]),
]


def render_lustre(lustre: Path, sc: dict, material: dict, spp: int, seed: int, tmp: Path, np):
    import mitsuba_plate as mp
    sc = json.loads(json.dumps(sc))
    sc["materials"]["plate"] = material
    text = mp.lustre_scene_text(sc, spp).replace(f"{sc['name']}.exr", str(tmp / "lustre.exr")) \
        .replace(f"{sc['name']}.png", str(tmp / "lustre.png")).replace("seed = 1", f"seed = {seed}")
    scene = tmp / "lustre.toml"
    scene.write_text(text)
    subprocess.run([str(lustre), str(scene), "--spp", str(spp)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    import mitsuba as mi
    return np.array(mi.Bitmap(str(tmp / "lustre.exr")), dtype=np.float64)[..., :3]


def render_mitsuba(sc: dict, bsdf_file: Path, spp: int, variant: str, seed: int, np):
    import mitsuba as mi
    import mitsuba_plate as mp
    mi.set_variant(variant)
    stand_in = json.loads(json.dumps(sc))
    stand_in["materials"]["plate"] = {"model": "ggx", "alpha": 0.2, "metal": "cu"}
    d = mp.mitsuba_scene_dict(mi, stand_in, spp)
    for k, v in d.items():
        if k.startswith("shape") and "bsdf" in v:
            v["bsdf"] = {"type": "measured", "filename": str(bsdf_file)}
    scene = mi.load_dict(d)
    img = mi.render(scene, spp=spp, seed=seed)
    return np.array(img, dtype=np.float64)[..., :3]


def view_angle(sc: dict) -> float:
    """Angle (radians) between the camera direction and the plate normal (+y)."""
    x, y, z = sc["camera"]["look_from"]
    return math.acos(y / math.sqrt(x * x + y * y + z * z))


def coherent_fraction(material: dict, theta: float, np):
    """GHS's coherent fraction A_s(λ) = exp(−(2kσ cosθ)²) at 360–830 nm (physics.md §3)."""
    lam = np.arange(360.0, 831.0, 5.0)
    k = 2.0 * math.pi / (lam * 1e-3)
    return lam, np.exp(-(2.0 * k * material["sigma_um"] * math.cos(theta)) ** 2)


def render_mitsuba_delta(sc: dict, material: dict, spp: int, variant: str, seed: int, np):
    """What the coherent lobe the table leaves out adds: the plate as a smooth conductor of
    the same metal scaled by A_s(λ) at the view angle (constant over the light's small
    mirror image, whose incidence varies by about a degree)."""
    import mitsuba as mi
    import mitsuba_plate as mp
    mi.set_variant(variant)
    stand_in = json.loads(json.dumps(sc))
    stand_in["materials"]["plate"] = {"model": "ggx", "alpha": 0.2, "metal": "cu"}
    d = mp.mitsuba_scene_dict(mi, stand_in, spp)
    eta, k = mp.metal_spectra(material["metal"], sc["name"])
    lam, a = coherent_fraction(material, view_angle(sc), np)
    scale = {"type": "irregular", "wavelengths": ", ".join(repr(float(x)) for x in lam),
             "values": ", ".join(repr(float(x)) for x in a)}
    for key, v in d.items():
        if key.startswith("shape") and "bsdf" in v:
            v["bsdf"] = {"type": "conductor", "eta": eta, "k": k, "specular_reflectance": scale}
    img = mi.render(mi.load_dict(d), spp=spp, seed=seed)
    return np.array(img, dtype=np.float64)[..., :3]


def blocks(np, a, b, size=32, lit=0.02):
    """Ratios b/a of the means of size x size blocks whose mean exceeds `lit` of the
    brightest block of a."""
    h, w = a.shape[:2]
    ma = a[: h // size * size, : w // size * size].reshape(h // size, size, w // size, size, 3).mean(axis=(1, 3))
    mb = b[: h // size * size, : w // size * size].reshape(h // size, size, w // size, size, 3).mean(axis=(1, 3))
    lum = ma.mean(axis=2)
    keep = lum > lit * lum.max()
    return (mb.mean(axis=2)[keep] / lum[keep]), keep.sum()


def plate(args) -> None:
    import numpy as np
    import mitsuba_plate as mp

    mp.set_llvm_path()
    import mitsuba as mi

    variant = "llvm_ad_spectral" if mp.llvm_works(mi) is None else "scalar_spectral"
    lustre = lustre_binary(args.lustre)
    with open(REPO / "benches" / "peer" / "plate_scenes.toml", "rb") as f:
        scenes = {s["name"]: s for s in tomllib.load(f)["scene"]}
    results = []
    with tempfile.TemporaryDirectory() as tmpd:
        tmp = Path(tmpd)
        for name, scene_name, material, flags in PLATES:
            if args.only and name not in args.only:
                continue
            sc = dict(scenes[scene_name], name=name)
            mat = tmp / f"{name}.toml"
            mat.write_text(toml_text(material))
            bsdf = tmp / f"{name}.bsdf"
            rep = subprocess.run([str(lustre), "brdf", "export", str(mat), "-o", str(bsdf)] + flags,
                                 check=True, capture_output=True, text=True).stdout
            chunks = [render_mitsuba(sc, bsdf, args.spp, variant, 1000 + k, np)
                      for k in range(args.chunks)]
            mi_img = np.mean(chunks, axis=0)
            lchunks = [render_lustre(lustre, sc, material, args.spp, 1 + k, tmp, np)
                       for k in range(args.chunks)]
            lu = np.mean(lchunks, axis=0)
            ratio_all = lu.mean(axis=(0, 1)) / mi_img.mean(axis=(0, 1))
            r, n = blocks(np, mi_img, lu)

            def rel_se(cs, mean):
                """Noise of an image mean from the spread of its chunks."""
                if len(cs) < 2:
                    return float("nan")
                return float(np.std([c.mean() for c in cs], ddof=1) / math.sqrt(len(cs)) / mean.mean())

            res = {"plate": name, "scene": scene_name, "material": material, "variant": variant,
                   "spp": args.spp * args.chunks,
                   "ratio_lustre_over_mitsuba_rgb": [float(x) for x in ratio_all],
                   "mitsuba_mean_rel_se": rel_se(chunks, mi_img),
                   "lustre_mean_rel_se": rel_se(lchunks, lu),
                   "blocks": int(n), "block_ratio_min": float(r.min()), "block_ratio_max": float(r.max()),
                   "block_ratio_median": float(np.median(r)), "export_report": rep.strip()}
            _, a_s = coherent_fraction(material, view_angle(sc), np) if "sigma_um" in material \
                else (None, np.zeros(1))
            if a_s.max() > 1e-4:
                delta = np.mean([render_mitsuba_delta(sc, material, args.spp, variant, 2000 + k, np)
                                 for k in range(args.chunks)], axis=0)
                both = mi_img + delta
                r2, _ = blocks(np, both, lu)
                res["coherent_fraction_max"] = float(a_s.max())
                res["ratio_lustre_over_mitsuba_plus_coherent_rgb"] = [
                    float(x) for x in lu.mean(axis=(0, 1)) / both.mean(axis=(0, 1))]
                res["block_ratio_with_coherent_min"] = float(r2.min())
                res["block_ratio_with_coherent_max"] = float(r2.max())
            results.append(res)
            print(json.dumps(res, indent=1), flush=True)
    out = HERE / "plates.json"
    # Plates not rendered this time keep their earlier results.
    done = {r["plate"] for r in results}
    if out.exists():
        old = json.loads(out.read_text()).get("plates", [])
        results = [r for r in old if r["plate"] not in done] + results
    order = [p[0] for p in PLATES]
    results.sort(key=lambda r: order.index(r["plate"]) if r["plate"] in order else len(order))
    tmpf = out.with_name(f".{out.name}.tmp")
    tmpf.write_text(json.dumps({"generator": "crates/export/validate/mitsuba_check.py plate",
                                "mitsuba": mi.__version__, "plates": results}, indent=1) + "\n")
    os.replace(tmpf, out)
    print(f"wrote {out}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["record", "plate"])
    ap.add_argument("--lustre", help="lustre binary")
    ap.add_argument("--rows", type=int, default=60, help="record: evaluations per case")
    ap.add_argument("--spp", type=int, default=64, help="plate: samples per pixel per chunk")
    ap.add_argument("--chunks", type=int, default=4, help="plate: Mitsuba renders (distinct seeds)")
    ap.add_argument("--only", nargs="*", help="plate: names of the plates to render")
    args = ap.parse_args()
    {"record": record, "plate": plate}[args.what](args)


if __name__ == "__main__":
    main()
