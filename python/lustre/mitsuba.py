"""A Mitsuba 3 BSDF plugin backed by :class:`lustre.Material` (Mitsuba's Python-BSDF
mechanism). ``register()`` then ``mi.load_dict({"type": "lustre", "model": "ghs",
"sigma_um": 0.138, "lc_um": 2.0, "gamma": 2.0, "metal": "cu"})``; every material key works.

Spectral variants evaluate at Mitsuba's sampled wavelengths (unset wavelengths, 0 nm, are
read as 550 nm); RGB and mono variants evaluate every channel at 550 nm. Directions are
sampled at the first (hero) wavelength; the other wavelengths get f(λ)·cosθo / pdf(λ₀).
In the JIT variants a call gets a whole wavefront, which the numpy path evaluates at once.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import Material

_UNSET_NM = 550.0


def register() -> None:
    """Registers the ``lustre`` BSDF in the current Mitsuba variant (set one first)."""
    import drjit as dr
    import mitsuba as mi

    scalar = mi.variant().startswith("scalar")

    def rows(v: Any) -> np.ndarray:
        a = np.asarray(v, dtype=np.float64).reshape(3, -1)
        return np.ascontiguousarray(a.T)

    def out(v: np.ndarray) -> Any:
        return float(v[0]) if scalar else mi.Float(np.ascontiguousarray(v, dtype=np.float32))

    def spectrum(vals: list[np.ndarray]) -> Any:
        if mi.is_spectral:
            return mi.Spectrum(*[out(v) for v in vals])
        if mi.is_rgb:
            return mi.Color3f(out(vals[0]), out(vals[0]), out(vals[0]))
        return mi.Spectrum(out(vals[0]))

    class LustreBSDF(mi.BSDF):
        def __init__(self, props: Any) -> None:
            mi.BSDF.__init__(self, props)
            keys = {}
            for k in props.keys():
                v = props[k]
                keys[k] = v if isinstance(v, (str, bool)) else float(v)
            self.keys = keys
            self.material = Material(**keys)
            flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def _lambdas(self, si: Any, n: int) -> np.ndarray:
            if not mi.is_spectral:
                return np.full((1, n), _UNSET_NM)
            lam = np.asarray(si.wavelengths, dtype=np.float64).reshape(4, -1)
            lam = np.where(lam > 0.0, lam, _UNSET_NM)
            return np.broadcast_to(lam, (4, n)) if lam.shape[1] == 1 else lam

        def _eval(self, si: Any, wo: Any) -> tuple[list[np.ndarray], np.ndarray]:
            wi, w = rows(si.wi), rows(wo)
            n = max(len(wi), len(w))
            lam = self._lambdas(si, n)
            cos = np.maximum(np.broadcast_to(w[:, 2], (n,)), 0.0)
            vals, pdf0 = [], None
            for k in range(lam.shape[0]):
                f, pdf = self.material.eval(wi, w, np.ascontiguousarray(lam[k]))
                vals.append(f * cos)
                pdf0 = pdf if pdf0 is None else pdf0
            return vals, pdf0

        def eval(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            vals, _ = self._eval(si, wo)
            return spectrum(vals)

        def pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            _, pdf = self._eval(si, wo)
            return out(pdf)

        def eval_pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            vals, pdf = self._eval(si, wo)
            return spectrum(vals), out(pdf)

        def sample(self, ctx: Any, si: Any, sample1: Any, sample2: Any, active: Any = True) -> Any:
            wi = rows(si.wi)
            u1 = np.asarray(sample1, dtype=np.float64).reshape(-1)
            u2 = np.asarray(sample2, dtype=np.float64).reshape(2, -1)
            n = max(len(wi), len(u1), u2.shape[1])
            u = np.ascontiguousarray(
                np.stack([np.broadcast_to(u2[0], (n,)), np.broadcast_to(u2[1], (n,)),
                          np.broadcast_to(u1, (n,))], axis=1)
            )
            lam = self._lambdas(si, n)
            wo, pdf, weight, delta = self.material.sample(wi, np.ascontiguousarray(lam[0]), u)
            vals = [weight]
            for k in range(1, lam.shape[0]):
                f, _ = self.material.eval(wi, wo, np.ascontiguousarray(lam[k]))
                with np.errstate(divide="ignore", invalid="ignore"):
                    w = np.where(pdf > 0.0, f * np.maximum(wo[:, 2], 0.0) / pdf, 0.0)
                vals.append(np.where(delta, weight, w))
            bs = mi.BSDFSample3f() if scalar else dr.zeros(mi.BSDFSample3f, n)
            if scalar:
                bs.wo = mi.Vector3f(*wo[0])
            else:
                bs.wo = mi.Vector3f(*(mi.Float(np.ascontiguousarray(wo[:, j], dtype=np.float32)) for j in range(3)))
            bs.pdf = out(pdf)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            return bs, spectrum(vals)

        def traverse(self, callback: Any) -> None:
            pass

        def parameters_changed(self, keys: Any) -> None:
            pass

        def to_string(self) -> str:
            return f"LustreBSDF[{self.material!r}]"

    mi.register_bsdf("lustre", lambda props: LustreBSDF(props))
