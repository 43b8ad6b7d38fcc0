"""Material: the numbers `lustre brdf eval` prints, bit for bit, for every model; the
array API's broadcasting, sampling and errors."""

import json
import math

import numpy as np
import pytest

import lustre
from conftest import loads_lines

MATERIALS = [
    dict(model="ggx", alpha=0.2, metal="cu"),
    dict(model="ggx", alpha_x=0.1, alpha_y=0.3, nk=[0.27, 3.4]),
    dict(model="beckmann", alpha=0.15, metal="au"),
    dict(model="smooth", metal="ag"),
    dict(model="ghs_ssa", sigma_um=0.05, lc_um=1.5, gamma=2.5, metal="al"),
    dict(model="ghs", sigma_um=0.138, lc_um=2.0, gamma=2.0, metal="cu"),
    dict(model="ghs", sigma_um=0.3, lc_um=4.0, gamma=3.0, fresnel="one"),
    dict(model="two_scale", beta=0.05, sigma_um=0.08, lc_um=1.0, gamma=2.2, metal="fe"),
    dict(model="rayleigh_rice", sigma_um=0.02, lc_um=1.0, gamma=2.0, metal="cu"),
    dict(model="ghs_ssa_aniso", sigma_um=0.05, lx_um=1.0, ly_um=3.0, angle_deg=20.0, gamma=2.5, metal="cu"),
]


def sincos_deg(deg: float) -> tuple[float, float]:
    """`lustre brdf eval`'s exact (sin, cos) of degrees (exact at multiples of 90°)."""
    r = deg % 360.0
    q = math.floor(r / 90.0)
    rest = r - 90.0 * q
    if rest == 0.0:
        s, c = 0.0, 1.0
    else:
        t = math.radians(rest)
        s, c = math.sin(t), math.cos(t)
    return [(s, c), (c, -s), (-s, -c), (-c, s)][int(q)]


def direction(theta: float, phi: float) -> list[float]:
    st, ct = sincos_deg(theta)
    sp, cp = sincos_deg(phi)
    return [st * cp, st * sp, ct]


GEOMETRY = [
    (ti, to, po, lam)
    for ti in (0.0, 30.0, 61.5, 85.0)
    for to in (0.0, 12.0, 30.0, 75.0, 90.0)
    for po in (180.0, 170.0, 90.0, 0.0)
    for lam in (450.0, 633.0)
]


@pytest.mark.parametrize("keys", MATERIALS, ids=lambda k: k["model"])
def test_eval_equals_brdf_eval_bit_for_bit(cli, keys):
    lines = [
        json.dumps({"lambda_nm": lam, "theta_i_deg": ti, "theta_o_deg": to, "phi_o_deg": po, **keys})
        for ti, to, po, lam in GEOMETRY
    ]
    want = loads_lines(cli("brdf", "eval", input="\n".join(lines) + "\n"))
    assert all("error" not in w for w in want), want[0]
    wi = np.array([direction(ti, 0.0) for ti, _, _, _ in GEOMETRY])
    wo = np.array([direction(to, po) for _, to, po, _ in GEOMETRY])
    lam = np.array([g[3] for g in GEOMETRY])
    m = lustre.Material(**keys)
    f, pdf = m.eval(wi, wo, lam)
    spec = m.specular(wi, lam)
    for i, w in enumerate(want):
        assert f[i] == w["f"], (GEOMETRY[i], f[i], w["f"])
        assert pdf[i] == w["pdf"], (GEOMETRY[i], pdf[i], w["pdf"])
        assert spec[i] == w["specular_weight"], (GEOMETRY[i], spec[i], w["specular_weight"])


def test_threaded_rows_equal_single_rows():
    """Past the parallel threshold the answer is the per-row one, row for row."""
    m = lustre.Material(model="ghs", sigma_um=0.138, lc_um=2.0, gamma=2.0, metal="cu")
    rng = np.random.default_rng(3)
    n = 20000
    wo = rng.normal(size=(n, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1)[:, None]
    wi = np.array([[0.5, 0.0, math.sqrt(0.75)]])
    lam = rng.uniform(400.0, 700.0, n)
    f, pdf = m.eval(wi, wo, lam)
    for i in rng.integers(0, n, 50):
        fi, pi = m.eval(wi, wo[i], lam[i])
        assert (fi[0], pi[0]) == (f[i], pdf[i])
    assert np.all(f >= 0) and np.any(f > 0)


@pytest.mark.parametrize("keys", [MATERIALS[0], MATERIALS[2], MATERIALS[5]], ids=lambda k: k["model"])
def test_sample_pdf_is_the_eval_pdf(keys):
    """A glossy sample's pdf is `pdf(wi, wo)` and its weight f·cosθo/pdf."""
    m = lustre.Material(**keys)
    rng = np.random.default_rng(1)
    n = 5000
    wi = np.array([[math.sin(0.6), 0.0, math.cos(0.6)]])
    u = rng.uniform(0.0, 1.0, (n, 3))
    wo, pdf, weight, delta = m.sample(wi, 550.0, u)
    ok = (~delta) & (pdf > 0)
    assert ok.sum() > n // 2
    f, p = m.eval(wi, wo[ok], 550.0)
    np.testing.assert_allclose(pdf[ok], p, rtol=1e-9)
    np.testing.assert_allclose(weight[ok], f * wo[ok, 2] / p, rtol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(wo[ok], axis=1), 1.0, rtol=1e-12)


def test_albedo_of_a_smooth_metal_is_its_fresnel_reflectance():
    m = lustre.Material(model="smooth", fresnel="one")
    np.testing.assert_allclose(m.albedo([0.0, 40.0, 80.0], 550.0), 1.0, rtol=1e-12)
    ggx = lustre.Material(model="ggx", alpha=0.3, fresnel="one")
    a = ggx.albedo([0.0, 60.0], [500.0, 600.0])
    assert np.all((a > 0.8) & (a <= 1.0 + 1e-9)), a


def test_help_lists_every_key_from_the_library_table():
    doc = lustre.Material.__doc__
    keys = lustre.material_keys()
    assert len(keys) > 20
    for key, ty, text, models in keys:
        assert f"    {key} ({ty};" in doc, key
        assert text and text in doc
    assert "sigma_um (f64; ghs_ssa, ghs" in doc


@pytest.mark.parametrize(
    "keys, key",
    [
        (dict(model="ggx", alpha=0.2, metal="cu", sigmaum=1.0), "sigmaum"),
        (dict(model="ggx", alpha="rough", metal="cu"), "alpha"),
        (dict(model="ggx", alpha=0.2, metal="unobtainium"), "metal"),
        (dict(model="ggx", alpha=0.2, metal="cu", gamma=2.0), "gamma"),
        (dict(model="ggx", alpha=0.2), "metal"),
        (dict(model="ghs", sigma_um=0.1, lc_um=2.0, gamma=0.5, metal="cu"), "gamma"),
        (dict(model="ggx", alpha=float("nan"), metal="cu"), "finite"),
    ],
)
def test_bad_keys_raise_value_error_naming_the_key(keys, key):
    with pytest.raises(ValueError, match=key):
        lustre.Material(**keys)


def test_bad_arrays_and_wavelengths_raise_value_error():
    m = lustre.Material(model="ggx", alpha=0.2, metal="cu")
    with pytest.raises(ValueError, match=r"wi: expected an array of shape \(N, 3\)"):
        m.eval(np.zeros((4, 2)), np.zeros((4, 3)), 550.0)
    with pytest.raises(ValueError, match="lambda_nm: 100"):
        m.eval([0, 0, 1], [0, 0, 1], 100.0)
    with pytest.raises(ValueError, match="rows"):
        m.eval(np.zeros((4, 3)), np.zeros((5, 3)), 550.0)
