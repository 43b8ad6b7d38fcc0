"""Speed of the Python API (a measurement, not a test): `Material.eval` throughput on
10^6 directions (GGX and full GHS) and the time to build a new full-GHS material.

    python python/bench.py [--n 1000000] [--repeat 5] [--builds 20]

Prints one line per measurement (best of `repeat`, wall clock, every core in use).
The numbers of record are in docs/python.md.
"""

import argparse
import math
import os
import sys
import time

import numpy as np

# `python python/bench.py` puts python/ first on the path, and its source folder lustre/
# (no compiled extension in it) would shadow the installed package.
_here = os.path.dirname(os.path.abspath(__file__))
sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != _here]

try:
    import lustre
except ImportError as e:
    sys.exit(f"bench.py measures the installed package: `pip install ./python` first ({e})")


def directions(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=1)[:, None]


def best(f, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--builds", type=int, default=20)
    a = ap.parse_args()
    print(f"lustre {lustre.__version__}, {os.cpu_count()} cores, n = {a.n}")
    wi = np.array([[math.sin(0.5), 0.0, math.cos(0.5)]])
    wo = directions(a.n, 1)
    lam = np.random.default_rng(2).uniform(400.0, 700.0, a.n)
    materials = {
        "ggx": lustre.Material(model="ggx", alpha=0.2, metal="cu"),
        "ghs (full)": lustre.Material(model="ghs", sigma_um=0.138, lc_um=2.0, gamma=2.0, metal="cu"),
    }
    for name, m in materials.items():
        m.eval(wi, wo[:1000], lam[:1000])
        t = best(lambda: m.eval(wi, wo, lam), a.repeat)
        print(f"eval {name:11s}: {a.n / t / 1e6:8.2f} M evaluations/s ({t * 1e3:.1f} ms for {a.n})")
    # A new surface each time: σ and γ change, so nothing is reused (the
    # process keeps a full-GHS table's diffraction orders per γ); then σ and
    # Lc change at one γ, as a fit or a sweep does, which reuses them.
    sweeps = {
        "new γ": lambda k: dict(sigma_um=0.1 + 0.001 * k, lc_um=2.0, gamma=2.0 + 0.01 * k),
        "same γ": lambda k: dict(sigma_um=0.1 + 0.001 * k, lc_um=1.0 + 0.01 * k, gamma=2.5),
    }
    for name, keys in sweeps.items():
        times = []
        for k in range(a.builds):
            t = time.perf_counter()
            lustre.Material(model="ghs", metal="cu", **keys(k))
            times.append(time.perf_counter() - t)
        times.sort()
        print(
            f"build new full-GHS material ({name}): median {times[len(times) // 2] * 1e3:.2f} ms, "
            f"best {times[0] * 1e3:.2f} ms ({a.builds} surfaces)"
        )


if __name__ == "__main__":
    main()
