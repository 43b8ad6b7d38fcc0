#!/usr/bin/env python3
"""Mitsuba 3 peer benchmark: rough-conductor plates at doubling sample counts.

Renders the scenes of plate_scenes.toml with Mitsuba 3 (scalar_spectral and, when the
machine's LLVM works, llvm_ad_spectral), timing every render (scene loading is timed
separately and excluded), and measures RMSE against a cached high-spp Mitsuba reference.

Outputs (in --out, default benches/peer/out/):
  timings.csv            scene,variant,spp,load_s,render_s,render_cpu_s,render_cold_s,
                         threads,loadavg_1min          (seconds; render_s = wall time)
  rmse.csv               scene,variant,spp,time_s,wall_s,rmse,rel_rmse,mse_ref_noise,
                         rmse_corrected,efficiency
                         time_s = CPU seconds of the render (all Mitsuba threads), the
                         quantity benches/error_vs_time.rs compares with lustre's CPU time;
                         rel_rmse = rmse / mean(reference); efficiency = 1/(time_s * rel_rmse^2)
  ref/<scene>.npy        reference image (linear sRGB, float32, H x W x 3) + .json metadata
  img/<scene>/<variant>_<spp>spp.{npy,exr}   every timed render (--no-images to skip)
  lustre_scenes/<scene>.toml   with --write-lustre-scenes: the same scenes for crates/render

Run benches/peer/setup.sh first. See benches/peer/README.md.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import os
import sys
import time
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent

REPO = HERE.parent.parent

# lustre metal names -> the repo's n,k tables (the same data lustre's brdf crate uses), so
# both renderers see identical Fresnel. Values: wavelength_nm,n,k CSV files.
METAL_TABLES = {
    "cu": "ior_Cu.csv", "copper": "ior_Cu.csv", "au": "ior_Au.csv", "gold": "ior_Au.csv",
    "ag": "ior_Ag.csv", "silver": "ior_Ag.csv", "al": "ior_Al.csv", "aluminium": "ior_Al.csv",
    "aluminum": "ior_Al.csv", "cr": "ior_Cr.csv", "chromium": "ior_Cr.csv", "fe": "ior_Fe.csv",
    "iron": "ior_Fe.csv", "brass": "ior_brass_Cu70Zn30.csv", "cu70zn30": "ior_brass_Cu70Zn30.csv",
    "stainless_steel": "ior_stainless_steel_austenitic.csv",
    "stainless": "ior_stainless_steel_austenitic.csv",
    "steel": "ior_stainless_steel_austenitic.csv",
    "stainless_steel_austenitic": "ior_stainless_steel_austenitic.csv",
}


class Unsupported(Exception):
    """A scene feature the Mitsuba translation does not cover."""


def metal_spectra(metal: str, where: str) -> tuple[dict, dict]:
    name = METAL_TABLES.get(metal.lower())
    if name is None:
        raise Unsupported(f"{where}: metal {metal!r} unknown; known: {sorted(METAL_TABLES)}")
    path = REPO / "data" / "spectra" / name
    rows = []
    with open(path) as f:
        for line in f:
            parts = line.strip().split(",")
            if len(parts) == 3:
                try:
                    rows.append(tuple(float(x) for x in parts))
                except ValueError:
                    pass  # header
    if len(rows) < 2:
        raise Unsupported(f"{path}: no wavelength_nm,n,k rows")
    wl = ", ".join(repr(r[0]) for r in rows)
    eta = {"type": "irregular", "wavelengths": wl, "values": ", ".join(repr(r[1]) for r in rows)}
    k = {"type": "irregular", "wavelengths": wl, "values": ", ".join(repr(r[2]) for r in rows)}
    return eta, k


def die(msg: str) -> None:
    print(f"mitsuba_plate.py: error: {msg}", file=sys.stderr)
    sys.exit(2)


def absolute_csv_paths(sc: dict, folder: Path) -> None:
    """Makes a material's `reflectance_csv`, a mesh's and an environment map's `file` absolute (they are relative to
    the scene file), so the Mitsuba translation and the lustre scene written into a temporary
    folder both find them."""
    for m in sc.get("materials", {}).values():
        if isinstance(m, dict) and isinstance(m.get("reflectance_csv"), str):
            m["reflectance_csv"] = str((folder / m["reflectance_csv"]).resolve())
    for s in sc.get("shapes", []):
        if isinstance(s, dict) and s.get("type") == "mesh" and isinstance(s.get("file"), str):
            s["file"] = str((folder / s["file"]).resolve())
    for l in sc.get("lights", []):
        if isinstance(l, dict) and l.get("type") == "environment" and isinstance(l.get("file"), str):
            l["file"] = str((folder / l["file"]).resolve())


def load_scenes(path: Path) -> list[dict]:
    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        die(f"cannot read scene description {path}: {e}")
    scenes = doc.get("scene")
    if not isinstance(scenes, list) or not scenes:
        die(f"{path}: expected one or more [[scene]] tables")
    names = [s.get("name") for s in scenes]
    if len(set(names)) != len(names) or None in names:
        die(f"{path}: every [[scene]] needs a unique `name` (got {names})")
    for sc in scenes:
        absolute_csv_paths(sc, path.parent)
    return scenes


# ---------------------------------------------------------------------------------------
# Scene translation (lustre scene format -> Mitsuba dict)

def rotation_xyz(mi, deg):
    """lustre applies rotate_deg as x, then y, then z."""
    T = mi.ScalarTransform4f
    return (T().rotate([0, 0, 1], deg[2]) @ T().rotate([0, 1, 0], deg[1])
            @ T().rotate([1, 0, 0], deg[0]))


def shape_transform(mi, tr: dict | None):
    T = mi.ScalarTransform4f
    tr = tr or {}
    m = T().translate(tr.get("translate", [0.0, 0.0, 0.0]))
    m = m @ rotation_xyz(mi, tr.get("rotate_deg", [0.0, 0.0, 0.0]))
    s = tr.get("scale", 1.0)
    return m @ T().scale(s if isinstance(s, list) else [s, s, s])


def y_normalisation_fix(mi) -> float:
    """Mitsuba's spectral film divides by MI_CIE_Y_NORMALIZATION⁻¹ = 106.7503 nm, but its
    own CIE 1931 ȳ table integrates to 106.8570 nm over 360–830 nm, so a uniform spectrum
    of value 1 renders at Y = 1.0010 (measured: a constant environment of 1, 4096 spp,
    gives XYZ = 1.0011, 1.0010, 1.0014), 0.1 % brighter than the colorimetric Y = 1 that
    lustre gives. This factor (0.99900) scales the translated uniform emitters so that
    both renderers mean the same radiance; it was the 0.09–0.11 % offset between them.
    Mitsuba's `d65` spectrum is normalised with the same constant and needs no fix
    (a constant D65 environment of scale 1 renders at Y = 0.99989)."""
    def scalar(v) -> float:  # a Python float in scalar variants, a 1-lane array in LLVM ones
        return float(v[0]) if hasattr(v, "__len__") else float(v)
    y = [scalar(mi.cie1931_y(float(l))) for l in range(360, 831)]
    integral = sum(0.5 * (a + b) for a, b in zip(y, y[1:]))
    return 1.0 / (float(mi.MI_CIE_Y_NORMALIZATION) * integral)


def spectrum(name: str, value: float, where: str, y_fix: float = 1.0) -> dict:
    """lustre spectra are normalised to unit luminance; on Mitsuba's spectral film a d65
    spectrum of scale v gives Y = v, a uniform one of value v gives Y = v / y_fix, so it
    is handed v · y_fix (see `y_normalisation_fix`)."""
    if name == "constant":
        return {"type": "uniform", "value": float(value) * y_fix}
    if name == "d65":
        return {"type": "d65", "scale": float(value)}
    raise Unsupported(f"{where}: spectrum {name!r} has no luminance-matched Mitsuba equivalent "
                      "here (use 'constant' or 'd65')")


def reflectance(sc: dict, m: dict, where: str) -> dict:
    """A diffuse reflectance: `reflectance = ρ` (Mitsuba's uniform spectrum) or
    `reflectance_csv` (rows wavelength_nm,ρ beside the scene file: an irregular spectrum, which
    Mitsuba interpolates linearly as lustre does). lustre's default base is Mitsuba's 0.5."""
    if "checker_reflectance" in m:
        # lustre's ρ0 squares are where i + j is even: Mitsuba 3's color0 (its spectral eval).
        import mitsuba as mi  # the caller has set the variant
        t = m.get("checker_tiles", [2.0, 2.0])
        r0, r1 = (float(v) for v in m["checker_reflectance"])
        return {"type": "checkerboard", "color0": {"type": "uniform", "value": r0},
                "color1": {"type": "uniform", "value": r1},
                "to_uv": mi.ScalarTransform4f().scale([t[0] / 2, t[1] / 2, 1.0])}
    if "reflectance_csv" in m:
        path = Path(m["reflectance_csv"])  # absolute: `absolute_csv_paths` at load
        rows = []
        try:
            with open(path) as f:
                for line in f:
                    parts = line.strip().split(",")
                    try:
                        rows.append((float(parts[0]), float(parts[1])))
                    except (ValueError, IndexError):
                        pass  # header or comment
        except OSError as e:
            raise Unsupported(f"{where}: cannot read reflectance_csv {path}: {e}")
        if len(rows) < 2:
            raise Unsupported(f"{where}: {path}: fewer than two wavelength_nm,reflectance rows")
        return {"type": "irregular", "wavelengths": ", ".join(repr(r[0]) for r in rows),
                "values": ", ".join(repr(r[1]) for r in rows)}
    return {"type": "uniform", "value": float(m.get("reflectance", 0.5))}


def roughplastic(sc: dict, m: dict, where: str) -> dict:
    """lustre's roughplastic is Mitsuba's (GGX coat over a Lambertian base, same keys); they
    differ by the documented amounts (physics.md §17: height-correlated G2 against Mitsuba's
    separable one; the internal reflectance R_i a converged integral where Mitsuba's 64-node
    rule is up to 1.6 % low)."""
    alpha = m.get("alpha", 0.1)
    if not isinstance(alpha, (int, float)) or not 1e-4 <= alpha <= 1.0:
        raise Unsupported(f"{where}: alpha must be a number in [1e-4, 1], got {alpha!r}")
    return {"type": "roughplastic", "distribution": "ggx", "alpha": float(alpha),
            "int_ior": float(m.get("int_ior", 1.49)), "ext_ior": float(m.get("ext_ior", 1.0)),
            "nonlinear": bool(m.get("nonlinear", False)), "sample_visible": True,
            "diffuse_reflectance": reflectance(sc, m, where)}


def material(sc: dict, mname: str) -> dict:
    where = f"scene {sc['name']}, materials.{mname}"
    m = sc.get("materials", {}).get(mname)
    if m is None:
        raise Unsupported(f"{where}: material not defined")
    if "include" in m:
        raise Unsupported(f"{where}: `include` (fitted material files) not supported by the peer script")
    model = m.get("model")
    if model == "diffuse":
        return {"type": "diffuse", "reflectance": reflectance(sc, m, where)}
    if model == "roughplastic":
        return roughplastic(sc, m, where)
    if model not in ("ggx", "beckmann"):
        raise Unsupported(f"{where}: model {model!r}: Mitsuba has only ggx and beckmann microfacets, "
                          "diffuse and roughplastic")
    alpha = m.get("alpha_beckmann", m.get("alpha")) if model == "beckmann" else m.get("alpha")
    if not isinstance(alpha, (int, float)) or not 1e-4 <= alpha <= 1.0:
        raise Unsupported(f"{where}: alpha must be a number in [1e-4, 1] (anisotropic alpha_x/alpha_y "
                          f"not translated), got {alpha!r}")
    bsdf = {"type": "roughconductor", "distribution": model, "alpha": float(alpha),
            "sample_visible": True}
    if m.get("fresnel", "conductor") == "one":
        bsdf["material"] = "none"  # Mitsuba: eta = 0, k = 1 -> a 100 % reflecting conductor
    elif "nk" in m:
        bsdf["eta"], bsdf["k"] = ({"type": "uniform", "value": float(v)} for v in m["nk"])
    elif "metal" in m:
        bsdf["eta"], bsdf["k"] = metal_spectra(str(m["metal"]), where)
    else:
        raise Unsupported(f"{where}: needs metal, nk or fresnel = 'one' (nk_csv not translated)")
    return bsdf


def mitsuba_scene_dict(mi, sc: dict, spp: int, resolution=None, sampler: str = "independent") -> dict:
    T = mi.ScalarTransform4f
    y_fix = y_normalisation_fix(mi)
    cam = sc["camera"]
    w, h = resolution or cam["resolution"]
    d = {
        "type": "scene",
        # lustre max_depth counts scattering events; Mitsuba counts the emitter vertex too.
        "integrator": {"type": "path", "max_depth": int(sc["integrator"]["max_depth"]) + 1,
                       "hide_emitters": False},
        "sensor": {
            "type": "perspective",
            "fov": float(cam["fov_deg"]),
            "fov_axis": "y",
            "to_world": T().look_at(origin=cam["look_from"], target=cam["look_at"],
                                    up=cam.get("up", [0.0, 1.0, 0.0])),
            "film": {"type": "hdrfilm", "width": int(w), "height": int(h),
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
            "sampler": {"type": sampler, "sample_count": int(spp)},
        },
    }
    for i, s in enumerate(sc.get("shapes", [])):
        where = f"scene {sc['name']}, shapes[{i}]"
        bsdf = material(sc, s.get("material", ""))
        if s["type"] == "rectangle":
            sx, sy = s["size"]
            # Mitsuba's rectangle spans [-1, 1]^2; lustre's spans size/2 either side.
            to_world = shape_transform(mi, s.get("transform")) @ T().scale([sx / 2, sy / 2, 1.0])
            d[f"shape{i}"] = {"type": "rectangle", "to_world": to_world, "bsdf": bsdf}
        elif s["type"] == "disk":
            r = s["radius"]
            to_world = shape_transform(mi, s.get("transform")) @ T().scale([r, r, 1.0])
            d[f"shape{i}"] = {"type": "disk", "to_world": to_world, "bsdf": bsdf}
        elif s["type"] == "sphere":
            d[f"shape{i}"] = {"type": "sphere", "center": s["center"], "radius": s["radius"],
                              "bsdf": bsdf}
        elif s["type"] == "mesh":
            # Both renderers interpolate the file's vertex normals (`vn`) as shading normals.
            d[f"shape{i}"] = {"type": "obj", "filename": s["file"], "bsdf": bsdf,
                              "to_world": shape_transform(mi, s.get("transform"))}
        else:
            raise Unsupported(f"{where}: shape type {s['type']!r} not supported by the peer script")
    for i, l in enumerate(sc.get("lights", [])):
        where = f"scene {sc['name']}, lights[{i}]"
        spec = l.get("spectrum", "d65")
        if l["type"] == "sphere":
            d[f"light{i}"] = {"type": "sphere", "center": l["center"], "radius": l["radius"],
                              "emitter": {"type": "area",
                                          "radiance": spectrum(spec, l["radiance"], where, y_fix)}}
        elif l["type"] == "point":
            d[f"light{i}"] = {"type": "point", "position": l["position"],
                              "intensity": spectrum(spec, l["intensity"], where, y_fix)}
        elif l["type"] == "rectangle":
            if l.get("two_sided", False):
                raise Unsupported(f"{where}: two_sided rectangle lights have no Mitsuba area-emitter "
                                  "equivalent here")
            sx, sy = l["size"]
            to_world = shape_transform(mi, l.get("transform")) @ T().scale([sx / 2, sy / 2, 1.0])
            # lustre's emitters reflect nothing; Mitsuba's default BSDF would be a 0.5 diffuse.
            d[f"light{i}"] = {"type": "rectangle", "to_world": to_world,
                              "bsdf": {"type": "diffuse", "reflectance": {"type": "uniform", "value": 0.0}},
                              "emitter": {"type": "area",
                                          "radiance": spectrum(spec, l["radiance"], where, y_fix)}}
        elif l["type"] == "environment" and "file" in l:
            if float(l.get("rotate_deg", 0.0)) != 0.0:
                raise Unsupported(f"{where}: rotate_deg of an environment map not translated")
            # Both map u = atan2(x, -z) / 2π, v = acos(y) / π (+y up). lustre looks the map up
            # texel by texel and lifts RGB onto the colour-matching functions; Mitsuba 3.9
            # interpolates bilinearly (no nearest option) and upsamples RGB its own way, so
            # images differ by that much and lustre is measured against its own reference.
            d[f"light{i}"] = {"type": "envmap", "filename": str(l["file"]),
                              "scale": float(l.get("radiance", 1.0))}
        elif l["type"] == "environment" and "file" not in l:
            d[f"light{i}"] = {"type": "constant", "radiance": spectrum(spec, l["radiance"], where, y_fix)}
        else:
            raise Unsupported(f"{where}: light type {l['type']!r} not supported by the peer script")
    return d


# ---------------------------------------------------------------------------------------
# lustre scene files

def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def lustre_scene_text(sc: dict, spp: int) -> str:
    out = [f"# {sc['name']}: {sc.get('description', '')}",
           "# Generated from benches/peer/plate_scenes.toml by mitsuba_plate.py.", ""]

    def table(header: str, t: dict):
        out.append(header)
        out.extend(f"{k} = {toml_value(v)}" for k, v in t.items())
        out.append("")

    table("[camera]", sc["camera"])
    table("[film]", {"spp": spp, "seed": 1, "exr": f"{sc['name']}.exr", "png": f"{sc['name']}.png"})
    table("[integrator]", sc["integrator"])
    for name, m in sc.get("materials", {}).items():
        table(f"[materials.{name}]", m)
    for s in sc.get("shapes", []):
        table("[[shapes]]", s)
    for l in sc.get("lights", []):
        table("[[lights]]", l)
    return "\n".join(out)


# ---------------------------------------------------------------------------------------
# Rendering

def atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)


def atomic_save_npy(np, path: Path, arr) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}.npy")
    np.save(tmp, arr)
    os.replace(tmp, path)


def render_timed(mi, dr, np, scene, spp: int, seed: int):
    """Renders and forces evaluation; returns (image as numpy HxWx3 float32, wall seconds,
    CPU seconds of the whole process, i.e. summed over Mitsuba's worker threads)."""
    c0, t0 = time.process_time(), time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    arr = np.array(img, dtype=np.float32)  # LLVM: waits for the kernel to finish
    dt, cpu = time.perf_counter() - t0, time.process_time() - c0
    return arr[..., :3], dt, cpu


def scene_hash(sc: dict, resolution) -> str:
    """Key of a cached reference: the scene with each `reflectance_csv` (an absolute path,
    so it would differ between checkouts) replaced by a hash of the file's bytes."""
    sc = json.loads(json.dumps(sc))
    for m in sc.get("materials", {}).values():
        if isinstance(m, dict) and isinstance(m.get("reflectance_csv"), str):
            try:
                m["reflectance_csv"] = hashlib.sha256(Path(m["reflectance_csv"]).read_bytes()).hexdigest()
            except OSError:
                pass  # unreadable: the path stays the key, and the translation reports it
    blob = json.dumps({"scene": sc, "res": resolution}, sort_keys=True).encode()
    return hashlib.sha256(blob).hexdigest()[:16]


def reference(mi, dr, np, sc, args, out: Path):
    """High-spp reference, rendered in chunks with distinct seeds and cached on disk.

    Returns (image, estimated per-pixel MSE of the reference itself, averaged)."""
    ref_dir = out / "ref"
    ref_dir.mkdir(parents=True, exist_ok=True)
    npy, meta_path = ref_dir / f"{sc['name']}.npy", ref_dir / f"{sc['name']}.json"
    # "translation" changes whenever mitsuba_scene_dict changes what it renders.
    key = {"hash": scene_hash(sc, args.resolution), "translation": 3, "spp": args.ref_spp,
           "variant": args.ref_variant, "sampler": args.ref_sampler, "mitsuba": mi.__version__}
    if npy.exists() and meta_path.exists() and not args.fresh_reference:
        meta = json.loads(meta_path.read_text())
        if all(meta.get(k) == v for k, v in key.items()):
            return np.load(npy), meta["mse_ref_noise"], meta
    mi.set_variant(args.ref_variant)
    chunk = min(args.ref_chunk, args.ref_spp)
    n = max(1, args.ref_spp // chunk)
    scene = mi.load_dict(mitsuba_scene_dict(mi, sc, chunk, args.resolution, args.ref_sampler))
    acc, acc2, total = None, None, 0.0
    for k in range(n):
        img, dt, _ = render_timed(mi, dr, np, scene, chunk, seed=10_000 + k)
        img = img.astype(np.float64)
        acc = img if acc is None else acc + img
        acc2 = img * img if acc2 is None else acc2 + img * img
        total += dt
        print(f"  reference {sc['name']}: chunk {k + 1}/{n} ({chunk} spp) {dt:.2f} s", flush=True)
    mean = acc / n
    # Variance of the mean over n chunk estimates: what the reference's own noise adds to
    # every measured MSE.
    mse_ref = float(np.mean((acc2 / n - mean * mean) / max(n - 1, 1))) if n > 1 else float("nan")
    ref = mean.astype(np.float32)
    atomic_save_npy(np, npy, ref)
    meta = dict(key, seconds=total, chunks=n, chunk_spp=chunk, mse_ref_noise=mse_ref,
                mean=float(ref.mean()))
    atomic_write_text(meta_path, json.dumps(meta, indent=1))
    try:
        mi.util.write_bitmap(str(ref_dir / f"{sc['name']}.exr"), ref)
    except Exception as e:  # EXR is a convenience; the NPY is the reference
        print(f"  (could not write reference EXR: {e})")
    return ref, mse_ref, meta


def set_llvm_path() -> None:
    """Dr.Jit's LLVM backend dlopen()s libLLVM; point it at Debian's libllvm19 unless the
    caller chose one. Must run before drjit is imported."""
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return
    for cand in ("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1", "/usr/lib/llvm-19/lib/libLLVM.so.1",
                 "/usr/lib/llvm-19/lib/libLLVM.so"):
        if os.path.exists(cand):
            os.environ["DRJIT_LIBLLVM_PATH"] = cand
            return


def llvm_works(mi) -> str | None:
    try:
        mi.set_variant("llvm_ad_spectral")
        import drjit as dr
        x = dr.llvm.Float([1.0, 2.0]) * 2.0
        dr.eval(x)
        return None
    except Exception as e:  # ImportError, RuntimeError("LLVM backend could not be initialised") ...
        return str(e)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", type=Path, default=HERE / "plate_scenes.toml")
    ap.add_argument("--out", type=Path, default=HERE / "out")
    ap.add_argument("--only", nargs="*", help="scene names to run (default: all)")
    ap.add_argument("--variants", default="scalar_spectral,llvm_ad_spectral")
    ap.add_argument("--samplers", default="independent",
                    help="comma-separated Mitsuba samplers (independent, stratified, multijitter, "
                         "orthogonal, ldsampler); non-default ones are labelled VARIANT+SAMPLER")
    ap.add_argument("--max-spp", type=int, default=256)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--ref-chunk", type=int, default=256)
    ap.add_argument("--ref-variant", default="llvm_ad_spectral")
    ap.add_argument("--ref-sampler", default="ldsampler",
                    help="sampler of the reference chunks (each chunk has its own seed, so chunks stay "
                         "independent and their spread estimates the reference's noise)")
    ap.add_argument("--fresh-reference", action="store_true")
    ap.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"))
    ap.add_argument("--no-images", action="store_true", help="do not save every timed render")
    ap.add_argument("--write-lustre-scenes", type=Path, metavar="DIR",
                    help="only write lustre scene TOML files for every scene to DIR and exit")
    ap.add_argument("--lustre-spp", type=int, default=64)
    ap.add_argument("--lustre-scene", type=Path, nargs="+", metavar="TOML",
                    help="render these lustre scene files (name = file stem) instead of --scenes; "
                         "files using features Mitsuba lacks (GHS models, blackbody spectra, ...) are skipped")
    ap.add_argument("--threads", type=int, help="Mitsuba worker threads (default: all cores; 1 hung scalar_spectral here)")
    ap.add_argument("--tag", default="", help="prefix for the CSV file names (e.g. 's138_')")
    args = ap.parse_args()

    if args.lustre_scene:
        scenes = []
        for p in args.lustre_scene:
            try:
                with open(p, "rb") as f:
                    sc = tomllib.load(f)
            except (OSError, tomllib.TOMLDecodeError) as e:
                die(f"cannot read lustre scene {p}: {e}")
            sc["name"] = p.stem
            absolute_csv_paths(sc, p.parent)
            sc.setdefault("integrator", {}).setdefault("max_depth", 8)
            scenes.append(sc)
    else:
        scenes = load_scenes(args.scenes)
    if args.only:
        unknown = set(args.only) - {s["name"] for s in scenes}
        if unknown:
            die(f"unknown scene(s) {sorted(unknown)}; known: {[s['name'] for s in scenes]}")
        scenes = [s for s in scenes if s["name"] in args.only]

    if args.write_lustre_scenes:
        args.write_lustre_scenes.mkdir(parents=True, exist_ok=True)
        for sc in scenes:
            atomic_write_text(args.write_lustre_scenes / f"{sc['name']}.toml",
                              lustre_scene_text(sc, args.lustre_spp))
        print(f"wrote {len(scenes)} lustre scenes to {args.write_lustre_scenes}")
        return

    set_llvm_path()
    try:
        import mitsuba as mi
        import drjit as dr
        import numpy as np
    except ImportError as e:
        die(f"{e}: run benches/peer/setup.sh first")

    # Translate every scene once up front so unsupported features fail (or are skipped) early.
    mi.set_variant("scalar_spectral")
    usable = []
    for sc in scenes:
        try:
            mitsuba_scene_dict(mi, sc, 1, args.resolution)
            usable.append(sc)
        except Unsupported as e:
            if not args.lustre_scene:
                die(str(e))
            print(f"skipping {sc['name']}: {e}", file=sys.stderr)
    scenes = usable
    if not scenes:
        die("no scene left to render")

    variants = [v for v in args.variants.split(",") if v]
    samplers = [v for v in args.samplers.split(",") if v]
    bad = [v for v in variants + [args.ref_variant] if v not in mi.variants()]
    if bad:
        die(f"variant(s) {bad} not in this Mitsuba build: {mi.variants()}")
    if any(v.startswith("llvm") for v in variants + [args.ref_variant]):
        err = llvm_works(mi)
        if err:
            print(f"LLVM variants unavailable ({err}); set DRJIT_LIBLLVM_PATH (see setup.sh). "
                  "Continuing with scalar variants only.", file=sys.stderr)
            variants = [v for v in variants if not v.startswith("llvm")]
            if args.ref_variant.startswith("llvm"):
                args.ref_variant = "scalar_spectral"
    if not variants:
        die("no usable variant left")

    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    spps = [1 << k for k in range(int(math.log2(args.max_spp)) + 1)]
    if args.threads:
        dr.set_thread_count(args.threads)
    threads = dr.thread_count()
    tim_rows, err_rows = [], []
    for sc in scenes:
        print(f"scene {sc['name']}", flush=True)
        ref, mse_ref, meta = reference(mi, dr, np, sc, args, out)
        ref_mean = float(ref.mean())
        for variant, sampler in [(v, smp) for v in variants for smp in samplers]:
            mi.set_variant(variant)
            label = variant if sampler == "independent" else f"{variant}+{sampler}"
            for spp in spps:
                t0 = time.perf_counter()
                scene = mi.load_dict(mitsuba_scene_dict(mi, sc, spp, args.resolution, sampler))
                load_s = time.perf_counter() - t0
                cold = float("nan")
                if variant.startswith("llvm"):
                    # First render of a kernel includes JIT compilation (or a kernel-cache
                    # lookup); report it, and time a second, warm render with another seed.
                    _, cold, _ = render_timed(mi, dr, np, scene, spp, seed=20_000 + spp)
                img, dt, cpu = render_timed(mi, dr, np, scene, spp, seed=spp)
                mse = float(np.mean((img.astype(np.float64) - ref) ** 2))
                rmse = math.sqrt(mse)
                corr = math.sqrt(max(mse - mse_ref, 0.0)) if not math.isnan(mse_ref) else float("nan")
                tim_rows.append([sc["name"], label, spp, f"{load_s:.6f}", f"{dt:.6f}", f"{cpu:.6f}",
                                 f"{cold:.6f}", threads, f"{os.getloadavg()[0]:.2f}"])
                rel_mse = (rmse / ref_mean) ** 2 if ref_mean > 0 else float("nan")
                err_rows.append([sc["name"], label, spp, f"{cpu:.6f}", f"{dt:.6f}", f"{rmse:.6e}",
                                 f"{rmse / ref_mean:.6e}", f"{mse_ref:.6e}", f"{corr:.6e}",
                                 f"{1.0 / (cpu * rel_mse):.6e}" if rel_mse > 0 and cpu > 0 else "inf"])
                print(f"  {label:30s} {spp:4d} spp  load {load_s:6.3f} s  render {dt:8.3f} s wall"
                      f" {cpu:8.3f} s CPU"
                      f"  rmse {rmse:.4e} (rel {rmse / ref_mean:.4e})", flush=True)
                if not args.no_images:
                    d = out / "img" / sc["name"]
                    d.mkdir(parents=True, exist_ok=True)
                    atomic_save_npy(np, d / f"{label}_{spp}spp.npy", img)
                    mi.util.write_bitmap(str(d / f"{label}_{spp}spp.exr"), img)
        # Rewrite the CSVs after every scene so an interrupted run keeps what it measured.
        write_csv(out / f"{args.tag}timings.csv", ["scene", "variant", "spp", "load_s", "render_s",
                  "render_cpu_s", "render_cold_s", "threads", "loadavg_1min"], tim_rows)
        write_csv(out / f"{args.tag}rmse.csv", ["scene", "variant", "spp", "time_s", "wall_s", "rmse",
                  "rel_rmse", "mse_ref_noise", "rmse_corrected", "efficiency"], err_rows)
    print(f"wrote {out / (args.tag + 'timings.csv')} and {out / (args.tag + 'rmse.csv')}")


def write_csv(path: Path, header: list[str], rows: list[list]) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    os.replace(tmp, path)


if __name__ == "__main__":
    main()
