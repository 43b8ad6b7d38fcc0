"""The Mitsuba 3 plugin (skipped unless `mitsuba` is installed; the LLVM variant also needs
libLLVM, found through DRJIT_LIBLLVM_PATH): Mitsuba's own chi-square test of the sampled
directions against the pdf for GGX, and eval = Material.eval · cosθo at Mitsuba's
wavelengths in scalar_spectral."""

import math
import os

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")

import lustre  # noqa: E402
import lustre.mitsuba  # noqa: E402

GHS = {"type": "lustre", "model": "ghs", "sigma_um": 0.138, "lc_um": 2.0, "gamma": 2.0, "metal": "cu"}


def test_scalar_spectral_eval_is_material_eval_times_cosine():
    mi.set_variant("scalar_spectral")
    lustre.mitsuba.register()
    b = mi.load_dict(GHS)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.5, 0.0, math.sqrt(0.75))
    si.wavelengths = mi.Spectrum(450.0, 500.0, 550.0, 650.0)
    wo = [-0.4, 0.1, math.sqrt(1 - 0.17)]
    got = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(*wo)))
    m = lustre.Material(**{k: v for k, v in GHS.items() if k != "type"})
    f, pdf = m.eval(np.array(si.wi), wo, [450.0, 500.0, 550.0, 650.0])
    np.testing.assert_allclose(got, f * wo[2], rtol=1e-6)
    assert b.pdf(mi.BSDFContext(), si, mi.Vector3f(*wo)) == pytest.approx(pdf[0], rel=1e-6)  # Mitsuba holds float32


@pytest.mark.skipif(not os.environ.get("DRJIT_LIBLLVM_PATH"), reason="needs DRJIT_LIBLLVM_PATH")
@pytest.mark.parametrize("wi", [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
def test_ggx_passes_mitsubas_chi2(wi):
    mi.set_variant("llvm_ad_rgb")
    lustre.mitsuba.register()
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    sample, pdf = BSDFAdapter("lustre", {"type": "lustre", "model": "ggx", "alpha": 0.3, "metal": "cu"}, wi=wi)
    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=3)
    assert chi2.run(), chi2.messages
