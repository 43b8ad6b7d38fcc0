#!/usr/bin/env python3
"""Writes studio_env.exr: a synthetic 256 x 128 lat-long HDR environment for the peer scenes
(generality_scenes_2.toml). Directions follow lustre's and Mitsuba's envmap convention,
d = (sin v·π sin u·2π, cos v·π, -sin v·π cos u·2π): a sky graded from a warm horizon (0.9, 0.85,
0.8) to a blue zenith (0.25, 0.4, 0.8), a dark ground (0.12, 0.1, 0.08), a softbox (18, 18, 17)
and a strip light (8, 9, 10) as rectangles in gnomonic coordinates, and a 2.5° sun (400, 380,
340). Needs numpy and mitsuba (for the EXR writer).

    python3 benches/peer/assets/make_studio_env.py
"""
from pathlib import Path

import numpy as np
import mitsuba as mi

W, H = 256, 128


def directions() -> np.ndarray:
    u = (np.arange(W) + 0.5) / W
    v = (np.arange(H) + 0.5) / H
    uu, vv = np.meshgrid(u, v)
    th, ph = vv * np.pi, uu * 2 * np.pi
    return np.stack([np.sin(th) * np.sin(ph), np.cos(th), -np.sin(th) * np.cos(ph)], -1)


def patch(img, d, center, half_w, half_h, radiance) -> None:
    c = np.array(center, float)
    c /= np.linalg.norm(c)
    t = np.cross([0, 1, 0], c)
    t /= np.linalg.norm(t)
    b = np.cross(c, t)
    x, y, z = d @ t, d @ b, d @ c
    zz = np.maximum(z, 1e-9)
    img[(z > 0) & (np.abs(x / zz) < half_w) & (np.abs(y / zz) < half_h)] = radiance


def main() -> None:
    mi.set_variant("scalar_rgb")
    d = directions()
    up = d[..., 1]
    sky = np.clip(up, 0, 1)[..., None]
    img = (up > 0)[..., None] * ((1 - sky) * np.array([0.9, 0.85, 0.8]) + sky * np.array([0.25, 0.4, 0.8]))
    img = img + (up <= 0)[..., None] * np.array([0.12, 0.1, 0.08])
    patch(img, d, [1.0, 0.6, 0.5], 0.25, 0.15, [18, 18, 17])
    patch(img, d, [-1.0, 0.9, -0.3], 0.12, 0.3, [8, 9, 10])
    sun = np.array([0.4, 0.64, -0.65])
    sun /= np.linalg.norm(sun)
    img[(d @ sun) > np.cos(np.radians(2.5))] = [400, 380, 340]
    mi.util.write_bitmap(str(Path(__file__).with_name("studio_env.exr")), img.astype(np.float32))


if __name__ == "__main__":
    main()
