"""A tour of the `lustre` Python package on the bundled data (run from the repository root):

    python python/examples/tour.py [--out out/python-tour]

Evaluates a full-GHS copper surface, reads and analyses a scan, fits a material to it,
judges the models against the scan's own explicit BRDF (a small crop, so it takes seconds),
renders the default scene with the fitted material, and writes the figures it makes:
`slices.csv` (an in-plane BRDF slice per model), `render.png` (8-bit sRGB) and, when
matplotlib is installed, `slices.png`.
"""

import argparse
import math
import struct
import zlib
from pathlib import Path

import numpy as np

import lustre


def write_png(path: Path, linear_rgb: np.ndarray) -> None:
    """8-bit sRGB PNG of a linear image (no dependency beyond zlib)."""
    c = np.clip(linear_rgb, 0.0, 1.0)
    srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    px = (srgb * 255 + 0.5).astype(np.uint8)
    h, w, _ = px.shape
    raw = b"".join(b"\x00" + px[y].tobytes() for y in range(h))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    path.write_bytes(png)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="out/python-tour")
    out = Path(ap.parse_args().out)
    out.mkdir(parents=True, exist_ok=True)

    # 1. Evaluate: an in-plane slice at 30° incidence, 550 nm, for three models.
    ti = math.radians(30.0)
    wi = np.array([[math.sin(ti), 0.0, math.cos(ti)]])
    to = np.radians(np.linspace(-89.0, 89.0, 357))
    wo = np.stack([np.sin(to), np.zeros_like(to), np.cos(to)], axis=1)
    models = {
        "ggx": lustre.Material(model="ggx", alpha=0.1, metal="cu"),
        "ghs_ssa": lustre.Material(model="ghs_ssa", sigma_um=0.138, lc_um=2.0, gamma=2.0, metal="cu"),
        "ghs": lustre.Material(model="ghs", sigma_um=0.138, lc_um=2.0, gamma=2.0, metal="cu"),
    }
    rows = ["theta_o_deg," + ",".join(models)]
    curves = {name: m.eval(wi, wo, 550.0)[0] for name, m in models.items()}
    for k, t in enumerate(np.degrees(to)):
        rows.append(f"{t:.1f}," + ",".join(f"{curves[n][k]:.6g}" for n in models))
    (out / "slices.csv").write_text("\n".join(rows) + "\n")
    for name, m in models.items():
        print(f"{name:8s} specular weight {m.specular(wi, 550.0)[0]:.4f}, "
              f"albedo at 30° {m.albedo(30.0, 550.0)[0]:.4f}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        for name in models:
            ax.semilogy(np.degrees(to), np.maximum(curves[name], 1e-6), label=name)
        ax.set(xlabel="θo (in plane) [deg]", ylabel="f [1/sr]", title="Cu, θi = 30°, 550 nm")
        ax.legend()
        fig.savefig(out / "slices.png", dpi=120)
    except ImportError:
        print("matplotlib not installed: slices.csv only")

    # 2. Read and analyse a scan (the dict `lustre fit stats --json` prints).
    scan = lustre.read_scan("data/surfaces/di-3.di")
    stats = scan.stats()
    print(f"{scan}: Sq {stats['sq_m'] * 1e6:.4f} µm, rms slope {stats['rms_slope']:.4f}, "
          f"KC σ {stats['kc']['sigma_m'] * 1e6:.4f} µm Lc {stats['kc']['lc_m'] * 1e6:.3f} µm")

    # 3. Fit a material file and build its model.
    material = lustre.fit(scan, metal="cu")
    print("fitted:", {k: material["material"][k] for k in ("model", "sigma_um", "lc_um", "gamma")})
    fitted = lustre.Material.from_fit(material)

    # 4. Judge the models against the explicit BRDF of the scan's heights (small crop).
    report = lustre.judge(scan, metal="cu", crop=128, angles=24, lambda_nm=[550.0],
                          theta_i_deg=[30.0], surrogate=False)
    print("judge keys:", sorted(report)[:8], "...")

    # 5. Render the default scene with the fitted material on the plate.
    import tomllib

    with open("scenes/default.toml", "rb") as f:
        scene = tomllib.load(f)
    scene["camera"]["resolution"] = [160, 120]
    scene["materials"]["steel"] = dict(fitted.keys)
    img = lustre.render(scene, spp=8, base_dir="scenes")
    write_png(out / "render.png", img)
    print(f"render: {img.shape}, mean {img.mean():.4f}; figures in {out}")


if __name__ == "__main__":
    main()
