"""The Mitsuba 3 plugin (skipped unless `mitsuba` is installed; the LLVM variants also need
libLLVM, found through DRJIT_LIBLLVM_PATH).

* Mitsuba's own chi-square test (`mitsuba.chi2.ChiSquareTest`) of the sampled directions
  against the plugin's pdf for GGX, Beckmann, full GHS and two-scale, in `llvm_ad_spectral`
  at the hero wavelength Mitsuba's sensor draws (so g is Mitsuba's λ's); models with a
  delta lobe are tested on their glossy component (the context's component selection),
  and the fraction of delta samples is checked against the probability the plugin reports
  and against its closed form. Lobes around the normal are tested on Mitsuba's spherical
  grid turned to put its pole on the horizon.
* Negative controls: the same chi-square test rejects the glossy sampler against the pdf
  that still carries the glossy choice 1 − p_δ, and against the pdf at another wavelength.
* eval = Material.eval · cosθo at Mitsuba's wavelengths (scalar_spectral), and the weights
  of the non-hero wavelengths of a sample are f(λ)·cosθo / pdf(λ₀) (glossy) or the delta
  weight at λ over p_δ(λ₀) (delta).
"""

import math
import os

import numpy as np
import pytest

# CI sets LUSTRE_REQUIRE_MITSUBA so that a missing mitsuba or libLLVM fails instead of skipping.
REQUIRED = bool(os.environ.get("LUSTRE_REQUIRE_MITSUBA"))
if REQUIRED:
    import drjit as dr
    import mitsuba as mi
else:
    mi = pytest.importorskip("mitsuba")
    dr = pytest.importorskip("drjit")

import lustre  # noqa: E402
import lustre.mitsuba  # noqa: E402

GHS = {"type": "lustre", "model": "ghs", "sigma_um": 0.138, "lc_um": 2.0, "gamma": 2.0, "metal": "cu"}
# The paper's S027 (stainless steel, σ 27 nm, Lc 1 µm, γ 4): a strong delta lobe whose share
# changes by half across the visible range.
S027 = {"type": "lustre", "model": "ghs", "sigma_um": 0.027, "lc_um": 1.0, "gamma": 4.0,
        "metal": "stainless_steel"}
# The paper's S138 two-scale split (scenes/samples/s138_two_scale_*.toml) with its coherent
# part as a delta lobe, and S808's with the default coherent part (a macro NDF of β 0.018).
TWO_SCALE = {"type": "lustre", "model": "two_scale", "sigma_um": 0.138, "lc_um": 2.0, "gamma": 2.0,
             "beta": 0.0007167256338107863, "metal": "brass", "coherent": "delta"}
TWO_SCALE_NDF = {"type": "lustre", "model": "two_scale", "sigma_um": 0.808, "lc_um": 10.0, "gamma": 3.5,
                 "beta": 0.01789208774834605, "metal": "stainless_steel"}
BECKMANN = {"type": "lustre", "model": "beckmann", "alpha": 0.3, "metal": "cu"}
GGX = {"type": "lustre", "model": "ggx", "alpha": 0.3, "metal": "cu"}

needs_llvm = pytest.mark.skipif(not REQUIRED and not os.environ.get("DRJIT_LIBLLVM_PATH"),
                                reason="needs DRJIT_LIBLLVM_PATH")


def material(d):
    return lustre.Material(**{k: v for k, v in d.items() if k != "type"})


def direction(theta_deg):
    t = math.radians(theta_deg)
    return [math.sin(t), 0.0, math.cos(t)]


def closed_form_delta_probability(sigma_um, cos_i, lambda_nm):
    """GHS with the default (raw) energy: p_δ = A_s = exp(−(4πσ cosθi/λ)²), floored at 5 %
    (lustre's minimum delta probability) while A_s ≥ 10⁻¹²."""
    a_s = math.exp(-((4.0 * math.pi * sigma_um * 1e3 * cos_i / lambda_nm) ** 2))
    return max(a_s, 0.05) if a_s >= 1e-12 else a_s


def glossy_context():
    ctx = mi.BSDFContext()
    ctx.component = lustre.mitsuba.GLOSSY_COMPONENT
    return ctx


def spectral_adapter(bsdf, wi, u_lambda, ctx=None, pdf_ctx=None, pdf_u_lambda=None):
    """Sampler and pdf for ChiSquareTest, as mitsuba.chi2.BSDFAdapter builds them, with the
    wavelengths Mitsuba's perspective sensor draws from `u_lambda` (the same on every lane,
    so the histogram is that of one hero wavelength). `pdf_ctx` / `pdf_u_lambda` give the
    pdf another context or wavelength (negative controls)."""
    mi.set_variant("llvm_ad_spectral")
    lustre.mitsuba.register()
    plugin = mi.load_dict(bsdf)
    sensor = mi.load_dict({"type": "perspective"})
    ctx = ctx or mi.BSDFContext()
    pdf_ctx = pdf_ctx or ctx
    pdf_u = u_lambda if pdf_u_lambda is None else pdf_u_lambda

    def interaction(n, u):
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(wi)
        si.wavelengths, _ = sensor.sample_wavelengths(si, dr.full(mi.Float, u, n))
        return si

    def sample(s):
        n = dr.width(s)
        bs, weight = plugin.sample(ctx, interaction(n, u_lambda), s[0], mi.Vector2f(s[1], s[2]))
        return bs.wo, dr.select(dr.all(weight == 0), 0.0, 1.0)

    def pdf(wo):
        return plugin.pdf(pdf_ctx, interaction(dr.width(wo), pdf_u), wo)

    return sample, pdf, plugin, interaction


def chi2(sample, pdf, ires=4, domain=None):
    """Mitsuba's test on its (φ, cosθ) grid of 202 × 101 cells. `ires` is the number of pdf
    evaluations per cell side of its trapezoid integration: Mitsuba's default 4 suits lobes
    wider than a cell; the wave-optical lobes (peaks of a few degrees, and the two-scale
    macro NDF of β ≈ 0.02) need 12, or the integrated pdf is off by up to 3 % where the
    histogram is right (S027 at 45°: χ² 969 on 680 d.o.f. at ires 4, 678 at ires 12)."""
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    return ChiSquareTest(domain=domain or SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=3,
                         ires=ires)


def tilted_domain():
    """Mitsuba's SphericalDomain turned so that its pole lies on the horizon (+x): a lobe
    around the normal then falls on its equator, where cells are about 1.8° × 1.1°, instead
    of the pole row, whose pdf integration fails for a lobe of a few degrees (full GHS at
    normal incidence, 424 nm: pdf sum 0.558 against a histogram of 0.538 at ires 12). A
    rotation keeps the solid-angle measure the test integrates with."""
    from mitsuba.chi2 import SphericalDomain

    class Tilted(SphericalDomain):
        def map_forward(self, p):
            v = SphericalDomain.map_forward(self, p)
            return mi.Vector3f(v.z, v.y, -v.x)

        def map_backward(self, d):
            return SphericalDomain.map_backward(self, mi.Vector3f(-d.z, d.y, d.x))

    return Tilted()


def hero_nm(u_lambda):
    mi.set_variant("llvm_ad_spectral")
    sensor = mi.load_dict({"type": "perspective"})
    lam, _ = sensor.sample_wavelengths(dr.zeros(mi.SurfaceInteraction3f, 1), mi.Float(u_lambda))
    return float(np.asarray(lam).reshape(4, -1)[0, 0])


def test_scalar_spectral_eval_is_material_eval_times_cosine():
    mi.set_variant("scalar_spectral")
    lustre.mitsuba.register()
    b = mi.load_dict(GHS)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.5, 0.0, math.sqrt(0.75))
    si.wavelengths = mi.Spectrum(450.0, 500.0, 550.0, 650.0)
    wo = [-0.4, 0.1, math.sqrt(1 - 0.17)]
    got = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(*wo)))
    m = material(GHS)
    f, pdf = m.eval(np.array(si.wi), wo, [450.0, 500.0, 550.0, 650.0])
    np.testing.assert_allclose(got, f * wo[2], rtol=1e-6)
    assert b.pdf(mi.BSDFContext(), si, mi.Vector3f(*wo)) == pytest.approx(pdf[0], rel=1e-6)  # Mitsuba holds float32
    # The glossy component alone: its pdf without the glossy choice 1 − p_δ(λ₀).
    p = closed_form_delta_probability(GHS["sigma_um"], math.sqrt(0.75), 450.0)
    assert b.pdf(glossy_context(), si, mi.Vector3f(*wo)) == pytest.approx(pdf[0] / (1 - p), rel=1e-5)
    delta_only = mi.BSDFContext()
    delta_only.component = lustre.mitsuba.DELTA_COMPONENT
    assert b.pdf(delta_only, si, mi.Vector3f(*wo)) == 0.0
    assert np.all(np.array(b.eval(delta_only, si, mi.Vector3f(*wo))) == 0.0)


@pytest.mark.parametrize("u1", [0.01, 0.6], ids=["delta", "glossy"])
def test_scalar_spectral_sample_is_material_sample(u1):
    # GHS at 70°, 450 nm: p_δ = 0.18, so sample1 = 0.01 draws the delta lobe, 0.6 the glossy one.
    mi.set_variant("scalar_spectral")
    lustre.mitsuba.register()
    b = mi.load_dict(GHS)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(direction(70.0))
    lam = [450.0, 520.0, 600.0, 700.0]
    si.wavelengths = mi.Spectrum(*lam)
    bs, weight = b.sample(mi.BSDFContext(), si, u1, mi.Point2f(0.3, 0.7))
    m = material(GHS)
    wi = np.array([direction(70.0)])
    wo, pdf, w0, is_delta = m.sample(wi, lam[0], [u1, 0.3, 0.7])
    assert bool(is_delta[0]) == (u1 < 0.1)
    assert int(bs.sampled_type) == int(mi.BSDFFlags.DeltaReflection if is_delta[0] else mi.BSDFFlags.GlossyReflection)
    np.testing.assert_allclose(np.array(bs.wo), wo[0], atol=1e-6)
    assert float(bs.pdf) == pytest.approx(pdf[0], rel=1e-6)
    f = [m.specular(wi, x)[0] if is_delta[0] else m.eval(wi, wo, x)[0][0] * wo[0, 2] for x in lam]
    np.testing.assert_allclose(np.array(weight), np.array(f) / pdf[0], rtol=1e-5)


def test_components_are_reported_as_mitsubas_multi_lobe_bsdfs_do():
    mi.set_variant("scalar_spectral")
    lustre.mitsuba.register()
    glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
    delta = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide
    for d, comps in [(GGX, [glossy]), (BECKMANN, [glossy]), (GHS, [glossy, delta]),
                     (S027, [glossy, delta]), (TWO_SCALE, [glossy, delta]), (TWO_SCALE_NDF, [glossy])]:
        b = mi.load_dict(d)
        assert [b.flags(i) for i in range(b.component_count())] == [int(c) for c in comps], d
        assert mi.has_flag(b.flags(), mi.BSDFFlags.DeltaReflection) == (len(comps) == 2)


@needs_llvm
@pytest.mark.parametrize("wi", [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
def test_ggx_passes_mitsubas_chi2(wi):
    mi.set_variant("llvm_ad_rgb")
    lustre.mitsuba.register()
    from mitsuba.chi2 import BSDFAdapter

    sample, pdf = BSDFAdapter("lustre", GGX, wi=wi)
    test = chi2(sample, pdf)
    assert test.run(quiet=True), test.messages


# (material, incidence [deg], u of Mitsuba's wavelength sample: 0.1 → λ₀ ≈ 424 nm,
# 0.5 → 546 nm, 0.9 → 686 nm). The GHS cases at 424 and 686 nm have g = 2.6× apart; the
# delta probability of the models with a delta lobe is 0.05–0.73 here, so testing the glossy
# component alone (the context's component selection) matters.
CHI2_CASES = [
    ("beckmann", BECKMANN, 0.0, 0.5),
    ("beckmann", BECKMANN, 60.0, 0.5),
    ("ghs", GHS, 30.0, 0.1),
    ("ghs", GHS, 30.0, 0.9),
    ("ghs", GHS, 70.0, 0.9),
    ("ghs_s027", S027, 45.0, 0.1),
    ("two_scale", TWO_SCALE, 70.0, 0.5),  # p_δ ≈ 0.31
    ("two_scale_macro_ndf", TWO_SCALE_NDF, 60.0, 0.9),
]


@needs_llvm
@pytest.mark.parametrize("name,bsdf,theta_deg,u_lambda", CHI2_CASES, ids=[
    f"{c[0]}-{c[2]:.0f}deg-u{c[3]}" for c in CHI2_CASES])
def test_glossy_component_passes_mitsubas_chi2_at_mitsubas_wavelength(name, bsdf, theta_deg, u_lambda):
    sample, pdf, _, _ = spectral_adapter(bsdf, direction(theta_deg), u_lambda, ctx=glossy_context())
    test = chi2(sample, pdf, ires=12)
    assert test.run(quiet=True), test.messages


@needs_llvm
@pytest.mark.parametrize("name,bsdf,u_lambda", [("ghs", GHS, 0.1), ("ghs", GHS, 0.9), ("ghs_s027", S027, 0.5)],
                         ids=["ghs-u0.1", "ghs-u0.9", "ghs_s027-u0.5"])
def test_glossy_component_at_normal_incidence_passes_mitsubas_chi2_on_a_tilted_grid(name, bsdf, u_lambda):
    sample, pdf, _, _ = spectral_adapter(bsdf, [0.0, 0.0, 1.0], u_lambda, ctx=glossy_context())
    test = chi2(sample, pdf, ires=12, domain=tilted_domain())
    assert test.run(quiet=True), test.messages


@needs_llvm
def test_chi2_rejects_the_pdf_with_the_lobe_choice_left_in():
    # The glossy sampler against the pdf of both lobes (which carries 1 − p_δ, p_δ ≈ 0.47).
    sample, pdf, _, _ = spectral_adapter(GHS, direction(70.0), 0.9, ctx=glossy_context(),
                                         pdf_ctx=mi.BSDFContext())
    test = chi2(sample, pdf, ires=12)
    assert not test.run(quiet=True), test.messages


@needs_llvm
def test_chi2_rejects_the_pdf_at_another_wavelength():
    # Directions drawn at λ₀ ≈ 424 nm, pdf at ≈ 686 nm (each passes alone at 30°, above):
    # the lobe's g differs by 2.6×.
    sample, pdf, _, _ = spectral_adapter(GHS, direction(30.0), 0.1, ctx=glossy_context(), pdf_u_lambda=0.9)
    test = chi2(sample, pdf, ires=12)
    assert not test.run(quiet=True), test.messages


def sample_many(plugin, interaction, ctx, n, seed):
    rng = np.random.default_rng(seed)
    u = rng.random((3, n))
    si = interaction(n)
    bs, weight = plugin.sample(ctx, si, mi.Float(u[0]), mi.Vector2f(mi.Float(u[1]), mi.Float(u[2])))
    return si, bs, np.asarray(weight, dtype=np.float64).reshape(4, -1)


@needs_llvm
@pytest.mark.parametrize("name,bsdf,theta_deg,u_lambda", [
    ("ghs", GHS, 70.0, 0.9), ("ghs_s027", S027, 0.0, 0.1), ("two_scale", TWO_SCALE, 70.0, 0.9)])
def test_delta_fraction_is_the_reported_probability(name, bsdf, theta_deg, u_lambda):
    n = 200_000
    _, _, plugin, interaction = spectral_adapter(bsdf, direction(theta_deg), u_lambda)
    si, bs, weight = sample_many(plugin, lambda m: interaction(m, u_lambda), mi.BSDFContext(), n, 7)
    kind = np.asarray(bs.sampled_type)
    comp = np.asarray(bs.sampled_component)
    is_delta = kind == int(mi.BSDFFlags.DeltaReflection)
    assert np.all(comp[is_delta] == lustre.mitsuba.DELTA_COMPONENT)
    assert np.all(comp[~is_delta] == lustre.mitsuba.GLOSSY_COMPONENT)
    assert np.all(kind[~is_delta] == int(mi.BSDFFlags.GlossyReflection))
    pdf = np.asarray(bs.pdf, dtype=np.float64)
    p = pdf[is_delta]
    assert p.size > 0 and np.ptp(p) < 1e-6, "one wi and λ₀: one delta probability"
    p = float(p[0])
    count = int(is_delta.sum())
    z = (count - n * p) / math.sqrt(n * p * (1 - p))
    assert abs(z) < 5.0, f"{count} delta samples of {n}, expected {n * p:.0f} (p = {p:.5f}), z = {z:.2f}"
    wo = np.asarray(bs.wo, dtype=np.float64).reshape(3, -1).T
    wi = np.array(direction(theta_deg))
    np.testing.assert_allclose(wo[is_delta], np.broadcast_to(wi * [-1, -1, 1], wo[is_delta].shape), atol=1e-6)
    if bsdf["model"] == "ghs":
        lam0 = hero_nm(u_lambda)
        assert p == pytest.approx(closed_form_delta_probability(bsdf["sigma_um"], wi[2], lam0), rel=1e-5)


@needs_llvm
@pytest.mark.parametrize("bsdf", [GHS, S027, TWO_SCALE, BECKMANN], ids=["ghs", "s027", "two_scale", "beckmann"])
@pytest.mark.parametrize("glossy_only", [False, True], ids=["both", "glossy"])
def test_every_wavelengths_weight_is_its_value_over_the_hero_pdf(bsdf, glossy_only):
    n = 4096
    theta = 40.0
    _, _, plugin, interaction = spectral_adapter(bsdf, direction(theta), 0.5)
    rng = np.random.default_rng(3)
    u_lambda = rng.random(n)
    sensor = mi.load_dict({"type": "perspective"})

    def varied(m):
        si = dr.zeros(mi.SurfaceInteraction3f, m)
        si.wi = mi.Vector3f(direction(theta))
        si.wavelengths, _ = sensor.sample_wavelengths(si, mi.Float(u_lambda))
        return si

    ctx = glossy_context() if glossy_only else mi.BSDFContext()
    si, bs, weight = sample_many(plugin, varied, ctx, n, 11)
    lam = np.asarray(si.wavelengths, dtype=np.float64).reshape(4, -1)
    pdf = np.asarray(bs.pdf, dtype=np.float64)
    wo = np.asarray(bs.wo, dtype=np.float64).reshape(3, -1).T
    is_delta = np.asarray(bs.sampled_type) == int(mi.BSDFFlags.DeltaReflection)
    if glossy_only:
        assert not is_delta.any()
    m = material(bsdf)
    wi = np.array([direction(theta)])
    ok = pdf > 0  # GHS: about 40 % of the glossy draws are evanescent (weight 0)
    assert ok.mean() > 0.5
    for k in range(4):
        f, _ = m.eval(wi, wo, lam[k])
        expect = np.where(is_delta, m.specular(wi, lam[k]), f * np.maximum(wo[:, 2], 0.0))
        np.testing.assert_allclose(weight[k][ok] * pdf[ok], expect[ok], rtol=2e-4, atol=1e-7)
    # The hero pdf is the plugin's own pdf of the sampled direction (glossy samples).
    g = ok & ~is_delta
    lam0_si = varied(n)
    got = np.asarray(plugin.pdf(ctx, lam0_si, bs.wo), dtype=np.float64)
    np.testing.assert_allclose(got[g], pdf[g], rtol=2e-4)


@needs_llvm
def test_a_plate_renders_in_llvm_ad_spectral():
    # A full-GHS plate under a uniform sky of radiance 1: every pixel sees the plate, which
    # reflects less than it receives (copper's albedo is below 1) and more than nothing.
    mi.set_variant("llvm_ad_spectral")
    lustre.mitsuba.register()
    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {"type": "perspective", "fov": 20.0,
                   "to_world": T().look_at(origin=[0.0, 1.0, 1.0], target=[0.0, 0.0, 0.0], up=[0.0, 1.0, 0.0]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 16}},
        "plate": {"type": "rectangle", "to_world": T().rotate([1.0, 0.0, 0.0], -90.0) @ T().scale(2.0), "bsdf": GHS},
        "sky": {"type": "constant"},
    })
    img = np.asarray(mi.render(scene), dtype=np.float64)[..., :3]
    assert np.all(np.isfinite(img))
    assert 0.2 < img.mean() < 1.0, img.mean()


@pytest.mark.parametrize("model", ["measured_psd2d_ssa", "measured_psd2d"])
def test_a_fit_files_2d_psd_model_is_material_eval_and_sample(cli, tmp_path, model):
    # corpus/mi-1's fit file carries a [psd.map] table, which the plugin reads through
    # `include` as a scene or `brdf eval` does.
    out = tmp_path / "mi1.toml"
    cli("fit", "data/surfaces/corpus/mi-1.mi", "--metal", "cu", "-o", str(out), "--no-plots")
    d = {"type": "lustre", "model": model, "include": str(out)}
    mi.set_variant("scalar_spectral")
    lustre.mitsuba.register()
    b = mi.load_dict(d)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(direction(40.0))
    lam = [450.0, 520.0, 600.0, 700.0]
    si.wavelengths = mi.Spectrum(*lam)
    m = material(d)
    wi = np.array([direction(40.0)])
    for wo in ([-0.55, 0.1, math.sqrt(1 - 0.3125)], [-0.3, -0.35, math.sqrt(1 - 0.2125)]):
        got = np.array(b.eval(glossy_context(), si, mi.Vector3f(*wo)))
        f, _ = m.eval(wi, wo, lam)
        assert f[0] > 0
        np.testing.assert_allclose(got, f * wo[2], rtol=1e-5)
    bs, weight = b.sample(glossy_context(), si, 0.5, mi.Point2f(0.3, 0.7))
    assert float(bs.pdf) > 0
    assert float(b.pdf(glossy_context(), si, bs.wo)) == pytest.approx(float(bs.pdf), rel=1e-5)
    f_wo = np.array(b.eval(glossy_context(), si, bs.wo))
    np.testing.assert_allclose(np.array(weight), f_wo / float(bs.pdf), rtol=1e-4)
