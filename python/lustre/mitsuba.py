"""A Mitsuba 3 BSDF plugin backed by :class:`lustre.Material` (Mitsuba's Python-BSDF
mechanism). ``register()`` then ``mi.load_dict({"type": "lustre", "model": "ghs",
"sigma_um": 0.138, "lc_um": 2.0, "gamma": 2.0, "metal": "cu"})``; every material key works.

Spectral variants evaluate at Mitsuba's sampled wavelengths (unset wavelengths, 0 nm, are
read as 550 nm); RGB and mono variants evaluate every channel at 550 nm. Directions are
sampled at the first (hero) wavelength λ₀; the other wavelengths get f(λ)·cosθo / pdf(λ₀)
for a glossy sample and their own delta weight over the delta probability at λ₀ for a
delta one, so every wavelength's estimate is unbiased.
In the JIT variants a call gets a whole wavefront, which the numpy path evaluates at once;
``register()`` therefore switches Dr.Jit's symbolic loops and calls off (``JitFlag``
``SymbolicLoops``, ``SymbolicCalls``), so that Mitsuba's integrators run in wavefront mode.

Components, as Mitsuba's own multi-lobe BSDFs report them: 0 is the glossy lobe
(``GlossyReflection``); models with a coherent specular lobe (full GHS, the SSA, two-scale
with ``coherent = "delta"``, smooth) add 1, the delta lobe (``DeltaReflection``). With both
enabled in the ``BSDFContext``, sampling picks the delta lobe with lustre's probability
p_δ(λ₀) and ``pdf`` includes the glossy choice 1 − p_δ, as ``Material`` does; with one
component selected (``ctx.component`` or ``ctx.type_mask``) only that lobe is sampled and
its pdf is that lobe's alone. The delta lobe's ``eval`` and ``pdf`` are 0.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import Material

_UNSET_NM = 550.0
GLOSSY_COMPONENT = 0
DELTA_COMPONENT = 1
# Incidence cosines and wavelengths at which a model is asked whether it has a delta lobe:
# its coherent fraction grows towards grazing incidence and long wavelengths, so a lobe that
# exists anywhere shows at the grazing end of this grid.
_PROBE_COS = (1.0, 0.3, 0.1, 0.03, 0.01, 0.001)
_PROBE_NM = (360.0, 550.0, 830.0)


def _has_delta(material: Material) -> bool:
    c = np.array(_PROBE_COS)
    wi = np.stack([np.sqrt(1.0 - c * c), np.zeros_like(c), c], axis=1)
    return any(bool(np.any(material.specular(wi, lam) > 0.0)) for lam in _PROBE_NM)


def register() -> None:
    """Registers the ``lustre`` BSDF in the current Mitsuba variant (set one first)."""
    import drjit as dr
    import mitsuba as mi

    scalar = mi.variant().startswith("scalar")
    if not scalar:
        # The plugin hands Mitsuba's arrays to numpy, which needs them evaluated; in a
        # symbolic loop or call they are not (Dr.Jit refuses: "remains dirty"), so the
        # integrators must run their loops and BSDF calls in evaluated (wavefront) mode.
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)

    def rows(v: Any) -> np.ndarray:
        a = np.asarray(v, dtype=np.float64).reshape(3, -1)
        return np.ascontiguousarray(a.T)

    def out(v: np.ndarray) -> Any:
        return float(v[0]) if scalar else mi.Float(np.ascontiguousarray(v, dtype=np.float32))

    def out_u32(v: np.ndarray) -> Any:
        return mi.UInt32(int(v[0])) if scalar else mi.UInt32(np.ascontiguousarray(v, dtype=np.uint32))

    def spectrum(vals: list[np.ndarray]) -> Any:
        if mi.is_spectral:
            return mi.Spectrum(*[out(v) for v in vals])
        if mi.is_rgb:
            return mi.Color3f(out(vals[0]), out(vals[0]), out(vals[0]))
        return mi.Spectrum(out(vals[0]))

    glossy_flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
    delta_flags = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide

    class LustreBSDF(mi.BSDF):
        def __init__(self, props: Any) -> None:
            mi.BSDF.__init__(self, props)
            keys = {}
            for k in props.keys():
                v = props[k]
                keys[k] = v if isinstance(v, (str, bool)) else float(v)
            self.keys = keys
            self.material = Material(**keys)
            self.has_delta = _has_delta(self.material)
            self.m_components = [glossy_flags] + ([delta_flags] if self.has_delta else [])
            self.m_flags = glossy_flags | delta_flags if self.has_delta else glossy_flags

        def _lobes(self, ctx: Any) -> tuple[bool, bool]:
            """(glossy, delta): which lobes the context enables."""
            glossy = bool(ctx.is_enabled(mi.BSDFFlags.GlossyReflection, GLOSSY_COMPONENT))
            delta = self.has_delta and bool(ctx.is_enabled(mi.BSDFFlags.DeltaReflection, DELTA_COMPONENT))
            return glossy, delta

        def _lambdas(self, si: Any, n: int) -> np.ndarray:
            if not mi.is_spectral:
                return np.full((1, n), _UNSET_NM)
            lam = np.asarray(si.wavelengths, dtype=np.float64).reshape(4, -1)
            lam = np.where(lam > 0.0, lam, _UNSET_NM)
            return np.ascontiguousarray(np.broadcast_to(lam, (4, n)) if lam.shape[1] == 1 else lam)

        def delta_probability(self, wi: np.ndarray, lam0: np.ndarray) -> np.ndarray:
            """p_δ(wi, λ₀) per row: the probability ``Material.sample`` picks the delta
            lobe (the pdf of a delta sample drawn with the lobe choice u₀ = 0)."""
            if not self.has_delta:
                return np.zeros(len(lam0))
            _, pdf, _, is_delta = self.material.sample(wi, lam0, [0.0, 0.5, 0.5])
            return np.where(is_delta, pdf, 0.0)

        def _glossy_pdf_scale(self, ctx: Any, wi: np.ndarray, lam0: np.ndarray) -> np.ndarray | float:
            """What turns Material's pdf (the glossy choice included) into the pdf of the
            enabled lobes: 1 with both lobes, 1/(1 − p_δ) with the glossy lobe alone."""
            glossy, delta = self._lobes(ctx)
            if not self.has_delta or delta:
                return 1.0
            p = self.delta_probability(wi, lam0)
            with np.errstate(divide="ignore"):
                return np.where(p < 1.0, 1.0 / (1.0 - p), 0.0)

        def _eval(self, ctx: Any, si: Any, wo: Any) -> tuple[list[np.ndarray], np.ndarray]:
            wi, w = rows(si.wi), rows(wo)
            n = max(len(wi), len(w))
            lam = self._lambdas(si, n)
            if not self._lobes(ctx)[0]:
                zero = np.zeros(n)
                return [zero] * lam.shape[0], zero
            cos = np.maximum(np.broadcast_to(w[:, 2], (n,)), 0.0)
            vals, pdf0 = [], None
            for k in range(lam.shape[0]):
                f, pdf = self.material.eval(wi, w, lam[k])
                vals.append(f * cos)
                pdf0 = pdf if pdf0 is None else pdf0
            return vals, pdf0 * self._glossy_pdf_scale(ctx, wi, lam[0])

        def eval(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            vals, _ = self._eval(ctx, si, wo)
            return spectrum(vals)

        def pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            _, pdf = self._eval(ctx, si, wo)
            return out(pdf)

        def eval_pdf(self, ctx: Any, si: Any, wo: Any, active: Any = True) -> Any:
            vals, pdf = self._eval(ctx, si, wo)
            return spectrum(vals), out(pdf)

        def _draw(self, ctx: Any, wi: np.ndarray, lam0: np.ndarray, u: np.ndarray) -> tuple:
            """(wo, pdf, hero weight, is_delta) of the enabled lobes at λ₀."""
            n = len(lam0)
            glossy, delta = self._lobes(ctx)
            if glossy and (delta or not self.has_delta):
                return self.material.sample(wi, lam0, u)
            p = self.delta_probability(wi, lam0)
            if delta:  # the delta lobe alone: drawn with probability 1
                spec = self.material.specular(wi, lam0)
                wo = np.broadcast_to(wi * [-1.0, -1.0, 1.0], (n, 3)).copy()
                ok = (p > 0.0) & (spec > 0.0)
                return np.where(ok[:, None], wo, 0.0), ok * 1.0, np.where(ok, spec, 0.0), ok
            if not glossy:
                z = np.zeros(n)
                return np.zeros((n, 3)), z, z, np.zeros(n, dtype=bool)
            # The glossy lobe alone: the lobe choice mapped past the delta's share.
            u = u.copy()
            u[:, 0] = np.minimum(p + u[:, 0] * (1.0 - p), np.nextafter(1.0, 0.0))
            wo, pdf, weight, is_delta = self.material.sample(wi, lam0, u)
            keep = (p < 1.0) & ~is_delta
            return (np.where(keep[:, None], wo, 0.0), np.where(keep, pdf / np.where(keep, 1.0 - p, 1.0), 0.0),
                    np.where(keep, weight * (1.0 - p), 0.0), np.zeros(n, dtype=bool))

        def sample(self, ctx: Any, si: Any, sample1: Any, sample2: Any, active: Any = True) -> Any:
            wi = rows(si.wi)
            u1 = np.asarray(sample1, dtype=np.float64).reshape(-1)
            u2 = np.asarray(sample2, dtype=np.float64).reshape(2, -1)
            n = max(len(wi), len(u1), u2.shape[1])
            # Material.sample reads u[0] as the lobe choice, u[1], u[2] for the direction:
            # Mitsuba's sample1 and sample2.
            u = np.ascontiguousarray(
                np.stack([np.broadcast_to(u1, (n,)), np.broadcast_to(u2[0], (n,)),
                          np.broadcast_to(u2[1], (n,))], axis=1)
            )
            lam = self._lambdas(si, n)
            wo, pdf, weight, delta = self._draw(ctx, wi, lam[0], u)
            vals = [weight]
            for k in range(1, lam.shape[0]):
                f, _ = self.material.eval(wi, wo, lam[k])
                spec = self.material.specular(wi, lam[k]) if np.any(delta) else 0.0
                with np.errstate(divide="ignore", invalid="ignore"):
                    glossy_w = np.where(pdf > 0.0, f * np.maximum(wo[:, 2], 0.0) / pdf, 0.0)
                    delta_w = np.where(pdf > 0.0, spec / pdf, 0.0)
                vals.append(np.where(delta, delta_w, glossy_w))
            bs = mi.BSDFSample3f() if scalar else dr.zeros(mi.BSDFSample3f, n)
            if scalar:
                bs.wo = mi.Vector3f(*wo[0])
            else:
                bs.wo = mi.Vector3f(*(mi.Float(np.ascontiguousarray(wo[:, j], dtype=np.float32)) for j in range(3)))
            bs.pdf = out(pdf)
            bs.eta = 1.0
            bs.sampled_type = out_u32(np.where(delta, int(mi.BSDFFlags.DeltaReflection),
                                               int(mi.BSDFFlags.GlossyReflection)))
            bs.sampled_component = out_u32(np.where(delta, DELTA_COMPONENT, GLOSSY_COMPONENT))
            return bs, spectrum(vals)

        def traverse(self, callback: Any) -> None:
            pass

        def parameters_changed(self, keys: Any) -> None:
            pass

        def to_string(self) -> str:
            return f"LustreBSDF[{self.material!r}]"

    mi.register_bsdf("lustre", lambda props: LustreBSDF(props))
