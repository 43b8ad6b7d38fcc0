"""Reference statistics of every real file in data/surfaces (top level, corpus/, formats/)
from SurfaceTopography, written to statistics.json beside this script.

Run: python3 st_statistics.py [FILE ...]  (SurfaceTopography 1.27.1, numpy; see README.md
here); with FILEs (paths relative to data/surfaces) only their entries are remade.

Each readable file is opened with SurfaceTopography's open_topography (unitless files in
their own numbers, as corpus/REFERENCE.json), its undefined points filled with
interpolate_undefined_data('harmonic'), levelled with detrend('height') (plane; line for
profiles). Then, about the mean of the levelled heights h:
  Sq  = rms_height_from_area (Rq = rms_height_from_profile for profiles)
  Sdq = rms_gradient (Rdq = rms_slope_from_profile)
  Sa  = mean |h|, Sz = max h - min h           (numpy on SurfaceTopography's heights)
  Ssk = mean h^3 / Sq^3, Sku = mean h^4 / Sq^4 (numpy; SurfaceTopography has none)
  acf_length = where the radially averaged normalised ACF 1 - A(r)/Sq^2 first falls to
     0.2, A being the non-periodic height-difference ACF
     A(k, l) = 1/2 <[h(i+k, j+l) - h(i, j)]^2> over the (nx-|k|)(ny-|l|) overlapping
     pairs, for lags k >= 0 and l of either sign (numpy, on SurfaceTopography's levelled
     heights), averaged in bins of width min(dx, dy) (bin b holds
     round(r / min(dx, dy)) == b), up to half the shorter side, crossing interpolated
     linearly between bin distances b * min(dx, dy).
  acf_length_st_quadrant = the same from SurfaceTopography's own map
     (autocorrelation_from_area(return_map=True)), which holds only lags with k, l >= 0:
     for an anisotropic scan it depends on the image's orientation (a flip of y changes
     it), which is why lustre averages both quadrants.
Lengths are in the file's unit ('unit'); null when SurfaceTopography found none.
"""
import hashlib
import json
import os
import sys

import numpy as np
from SurfaceTopography import open_topography

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SETS = [("", ROOT), ("corpus", os.path.join(ROOT, "corpus")), ("formats", os.path.join(ROOT, "formats"))]
THRESHOLD = 0.2


def radial_length(a_map, dx, dy, sq):
    """Where the radially averaged 1 - A/Sq^2 first falls to THRESHOLD."""
    rho = 1.0 - np.asarray(a_map, dtype=float) / sq**2
    if rho.ndim == 1:
        k = np.arange(rho.size)
        r = k * dx
        step = dx
        rmax = rho.size * dx / 2
    else:
        k, l = np.meshgrid(np.arange(rho.shape[0]), np.arange(rho.shape[1]), indexing="ij")
        r = np.hypot(k * dx, l * dy)
        step = min(dx, dy)
        rmax = min(rho.shape[0] * dx, rho.shape[1] * dy) / 2
    b = np.rint(r / step).astype(int)
    keep = (r <= rmax) & np.isfinite(rho)
    nb = b[keep].max() + 1
    sums = np.bincount(b[keep], weights=rho[keep], minlength=nb)
    counts = np.bincount(b[keep], minlength=nb)
    prev = None
    for i in range(nb):
        if counts[i] == 0:
            continue
        v = sums[i] / counts[i]
        if v <= THRESHOLD:
            if prev is None:
                return 0.0
            (i0, v0) = prev
            return (i0 + (v0 - THRESHOLD) / (v0 - v) * (i - i0)) * step
        prev = (i, v)
    return None


def full_acf_map(h):
    """A(k, l) for k in [0, nx), l in (-ny, ny) (row index l + ny - 1), non-periodic."""
    nx, ny = h.shape
    px, py = 2 * nx, 2 * ny
    f = np.fft.fft2(h, s=(px, py))
    c = np.real(np.fft.ifft2(f * np.conj(f)))  # c[k, l] = sum h(i, j) h(i+k, j+l)
    h2 = h**2
    pre = np.zeros((nx + 1, ny + 1))
    pre[1:, 1:] = np.cumsum(np.cumsum(h2, axis=0), axis=1)

    def rect(x0, y0, x1, y1):
        return pre[x1, y1] - pre[x0, y1] - pre[x1, y0] + pre[x0, y0]

    out = np.zeros((nx, 2 * ny - 1))
    for li, l in enumerate(range(-(ny - 1), ny)):
        for k in range(nx):
            pairs = (nx - k) * (ny - abs(l))
            cc = c[k, l % py]
            if l >= 0:
                s1, s2 = rect(0, 0, nx - k, ny - l), rect(k, l, nx, ny)
            else:
                s1, s2 = rect(0, -l, nx - k, ny), rect(k, 0, nx, ny + l)
            out[k, li] = 0.5 * (s1 + s2) / pairs - cc / pairs
    return out


def radial_full(a_map, dx, dy, sq):
    nx = a_map.shape[0]
    ny = (a_map.shape[1] + 1) // 2
    k, l = np.meshgrid(np.arange(nx), np.arange(-(ny - 1), ny), indexing="ij")
    rho = 1.0 - a_map / sq**2
    r = np.hypot(k * dx, l * dy)
    step = min(dx, dy)
    rmax = min(nx * dx, ny * dy) / 2
    return crossing(rho, r, step, rmax)


def crossing(rho, r, step, rmax):
    b = np.rint(r / step).astype(int)
    keep = (r <= rmax) & np.isfinite(rho)
    nb = b[keep].max() + 1
    sums = np.bincount(b[keep], weights=rho[keep], minlength=nb)
    counts = np.bincount(b[keep], minlength=nb)
    prev = None
    for i in range(nb):
        if counts[i] == 0:
            continue
        v = sums[i] / counts[i]
        if v <= THRESHOLD:
            if prev is None:
                return 0.0
            (i0, v0) = prev
            return (i0 + (v0 - THRESHOLD) / (v0 - v) * (i - i0)) * step
        prev = (i, v)
    return None


def stats(path):
    r = open_topography(path)
    t = r.topography()
    entry = {"reader": type(r).__name__, "dim": t.dim, "unit": t.unit,
             "nb_grid_pts": [int(n) for n in t.nb_grid_pts],
             "physical_sizes": [float(s) for s in t.physical_sizes]}
    if t.has_undefined_data:
        entry["undefined"] = True
        t = t.interpolate_undefined_data("harmonic")
    t = t.detrend("height")
    if not t.is_uniform:
        # A non-uniform profile: SurfaceTopography integrates the piecewise-linear line
        # (lustre resamples it); only its Rq and Rdq are recorded.
        entry["uniform"] = False
        entry["Sq"] = float(t.rms_height_from_profile())
        entry["Sdq"] = float(t.rms_slope_from_profile())
        return entry
    h = np.asarray(t.heights(), dtype=float)
    h = h - h.mean()
    sq = float(np.sqrt(np.mean(h**2)))
    if t.dim == 2:
        entry["Sq"] = float(t.rms_height_from_area())
        entry["Sdq"] = float(t.rms_gradient())
        dx, dy = (float(p) for p in t.pixel_size)
        _, _, a_map = t.autocorrelation_from_area(return_map=True)
    else:
        entry["Sq"] = float(t.rms_height_from_profile())
        entry["Sdq"] = float(t.rms_slope_from_profile())
        dx = dy = float(t.pixel_size[0])
        n = h.size
        a_map = np.array([0.5 * np.mean((h[: n - k] - h[k:]) ** 2) for k in range(n)])
    entry["Sa"] = float(np.mean(np.abs(h)))
    entry["Sz"] = float(h.max() - h.min())
    entry["Ssk"] = float(np.mean(h**3) / sq**3) if sq > 0 else None
    entry["Sku"] = float(np.mean(h**4) / sq**4) if sq > 0 else None
    if sq > 0 and t.dim == 2:
        entry["acf_length"] = radial_full(full_acf_map(h), dx, dy, sq)
        entry["acf_length_st_quadrant"] = radial_length(a_map, dx, dy, sq)
    elif sq > 0:
        entry["acf_length"] = radial_length(a_map, dx, dy, sq)
    else:
        entry["acf_length"] = None
    return entry


def main():
    # With file arguments (relative to data/surfaces), only their entries are remade and
    # the others kept as they are.
    only = set(sys.argv[1:])
    previous = {}
    if only:
        with open(os.path.join(HERE, "statistics.json")) as f:
            previous = {e["file"]: e for e in json.load(f)["files"]}
    out = []
    for set_name, folder in SETS:
        for name in sorted(os.listdir(folder)):
            path = os.path.join(folder, name)
            if not os.path.isfile(path) or name.endswith((".md", ".json", ".py")):
                continue
            rel = os.path.join(set_name, name) if set_name else name
            if only and rel not in only:
                if rel in previous:
                    out.append(previous[rel])
                continue
            with open(path, "rb") as f:
                sha = hashlib.sha256(f.read()).hexdigest()
            try:
                e = stats(path)
            except Exception as exc:  # noqa: BLE001 - recorded as SurfaceTopography's refusal
                e = {"error": f"{type(exc).__name__}: {str(exc)[:200]}"}
            e = {"file": rel, "sha256": sha, **e}
            print(rel, e.get("Sq"), e.get("error", ""), file=sys.stderr)
            out.append(e)
    about = __doc__.strip()
    with open(os.path.join(HERE, "statistics.json"), "w") as f:
        json.dump({"about": about, "surface_topography": "1.27.1", "files": out}, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
