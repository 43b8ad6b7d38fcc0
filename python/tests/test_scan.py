"""Scans: `stats()` is the dict `lustre fit stats --json` prints, `fit()` the material
file `lustre fit` writes and `judge()` the report `lustre judge --json` prints, each
equal to the CLI's to the last bit; arrays and files give the same analysis."""

import json
import math
import tomllib

import numpy as np
import pytest

import lustre
from conftest import SURFACES, loads_lines
from test_material import direction

STATS_FILES = ["dektak-1.csv", "di-3.di", "matrix-3.txt", "formats/sdf-1.sdf", "formats/xy-2.txt"]


@pytest.mark.parametrize("name", STATS_FILES)
def test_stats_equal_fit_stats_json(cli, name):
    path = f"data/surfaces/{name}"
    want = json.loads(cli("fit", "stats", path, "--json"))
    got = lustre.read_scan(path).stats()
    assert got == want


def test_stats_options_are_the_cli_flags(cli):
    path = "data/surfaces/di-3.di"
    want = json.loads(cli("fit", "stats", path, "--json", "--level", "poly2", "--outliers", "mask"))
    got = lustre.read_scan(path).stats(level="poly2", outliers="mask")
    assert got == want
    assert got["level"]["kind"] == "poly2"


def test_an_array_gives_the_analysis_of_the_file():
    scan = lustre.read_scan("data/surfaces/di-3.di")
    assert scan.heights.shape[1] > 1 and scan.heights.dtype == np.float64
    copy = lustre.Scan(scan.heights, scan.dx, scan.dy, name=scan.name)
    a, b = scan.stats(), copy.stats()
    for k in ("sq_m", "rms_slope", "kc", "psd", "iso25178", "anisotropy", "grid", "pixel_m"):
        assert a[k] == b[k], k
    assert b["format"] == "array"
    profile = lustre.read_scan(np.sin(np.arange(512) * 0.3) * 1e-7, dx=1e-7)
    assert profile.heights.shape == (1, 512) and profile.dy == profile.dx


def nan_to_none(v):
    if isinstance(v, float) and math.isnan(v):
        return None
    if isinstance(v, dict):
        return {k: nan_to_none(x) for k, x in v.items()}
    if isinstance(v, list):
        return [nan_to_none(x) for x in v]
    return v


@pytest.mark.parametrize("name, metal", [("di-3.di", "cu"), ("dektak-1.csv", "stainless_steel")])
def test_fit_equals_the_material_file(cli, tmp_path, name, metal):
    path = f"data/surfaces/{name}"
    out = tmp_path / "m.toml"
    cli("fit", path, "--metal", metal, "-o", str(out), "--no-plots")
    want = tomllib.loads(out.read_text())
    got = lustre.fit(path, metal=metal)
    assert nan_to_none(got) == nan_to_none(want)
    m = lustre.Material.from_fit(got)
    f, _ = m.eval([0, 0, 1], [0.1, 0, math.sqrt(0.99)], 550.0)
    assert f[0] > 0


def test_judge_equals_judge_json(cli, tmp_path):
    path = "data/surfaces/di-3.di"
    flags = dict(crop=64, angles=16, lambda_nm=[550.0], theta_i_deg=[30.0], surrogate=False)
    want = json.loads(
        cli("judge", path, "--json", "--no-plots", "-o", str(tmp_path), "--crop", "64",
            "--angles", "16", "--lambda", "550", "--theta-i", "30", "--no-surrogate", "--metal", "cu")
    )
    got = lustre.judge(path, metal="cu", **flags)
    assert got == want


def test_read_errors_are_os_and_value_errors(tmp_path):
    with pytest.raises(OSError, match="nope.x3p"):
        lustre.read_scan(tmp_path / "nope.x3p")
    bad = tmp_path / "bad.x3p"
    bad.write_bytes(b"not a zip at all")
    with pytest.raises(ValueError, match="bad.x3p"):
        lustre.read_scan(bad)
    with pytest.raises(ValueError, match="units"):
        lustre.read_scan(SURFACES / "dektak-1.csv", units="furlongs")
    with pytest.raises(ValueError, match="dx"):
        lustre.Scan(np.zeros((4, 4)), dx=-1.0)
    with pytest.raises(ValueError, match="level"):
        lustre.read_scan(SURFACES / "di-3.di").stats(level="quartic")


def _stretched_map(angle_deg, n=256, dx=0.1e-6, lx=0.4e-6, ly=1.6e-6, seed=7):
    """A Gaussian random surface whose correlation lengths are lx across the lay and ly
    along it, the lay's normal at angle_deg from x towards y (heights ~ 20 nm rms)."""
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(n, d=dx) * 2 * np.pi
    kx, ky = np.meshgrid(k, k)
    a = math.radians(angle_deg)
    u = kx * math.cos(a) + ky * math.sin(a)
    v = -kx * math.sin(a) + ky * math.cos(a)
    psd = (1 + (u * lx) ** 2 + (v * ly) ** 2) ** -2.0
    h = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * np.sqrt(psd)))
    return h / h.std() * 20e-9


@pytest.mark.parametrize("angle_deg", [0.0, 35.0, 110.0])
def test_from_fit_builds_what_an_include_of_the_file_builds(tmp_path, angle_deg):
    scan = lustre.Scan(_stretched_map(angle_deg), 0.1e-6, 0.1e-6, name="stretched")
    got = lustre.fit(scan, metal="cu")
    mat = got["material"]
    assert "angle_deg" in mat and mat["alpha_x"] != mat["alpha_y"], mat
    # The lay's normal is recovered (mod 180°).
    d = (mat["angle_deg"] - angle_deg + 90.0) % 180.0 - 90.0
    assert abs(d) < 5.0, (mat["angle_deg"], angle_deg)
    turned = lustre.Material.from_fit(got, model="ggx")
    by_hand = lustre.Material(
        model="ggx", alpha_x=mat["alpha_x"], alpha_y=mat["alpha_y"],
        angle_deg=mat["angle_deg"], metal="cu",
    )
    rng = np.random.default_rng(1)
    wi = rng.normal(size=(64, 3)); wi[:, 2] = abs(wi[:, 2]); wi /= np.linalg.norm(wi, axis=1)[:, None]
    wo = rng.normal(size=(64, 3)); wo[:, 2] = abs(wo[:, 2]); wo /= np.linalg.norm(wo, axis=1)[:, None]
    f1, p1 = turned.eval(wi, wo, 550.0)
    f2, p2 = by_hand.eval(wi, wo, 550.0)
    assert np.array_equal(f1, f2) and np.array_equal(p1, p2)
    # Turning matters: the same pair along the tangent axes differs.
    flat = lustre.Material(model="ggx", alpha_x=mat["alpha_x"], alpha_y=mat["alpha_y"], metal="cu")
    if abs(math.sin(2 * math.radians(mat["angle_deg"]))) > 0.3:
        assert not np.allclose(flat.eval(wi, wo, 550.0)[0], f1)
    assert turned.keys["angle_deg"] == mat["angle_deg"]
    # The file's own PSD answers a measured-PSD model without writing the file.
    measured = lustre.Material.from_fit(got, model="measured_psd")
    assert measured.eval([0, 0, 1], [0.05, 0, math.sqrt(1 - 0.0025)], 550.0)[0][0] > 0


def test_from_fit_takes_a_parsed_file_and_names_a_bad_key(cli, tmp_path):
    out = tmp_path / "m.toml"
    cli("fit", "data/surfaces/di-3.di", "--metal", "cu", "-o", str(out), "--no-plots")
    parsed = tomllib.loads(out.read_text())
    a = lustre.Material.from_fit(parsed, model="ghs_ssa")
    b = lustre.Material(include=str(out), model="ghs_ssa")
    wo = [0.2, 0.1, math.sqrt(0.95)]
    assert a.eval([0, 0, 1], wo, 550.0)[0][0] == b.eval([0, 0, 1], wo, 550.0)[0][0]
    with pytest.raises(ValueError, match="alpha_z"):
        lustre.Material.from_fit(parsed, alpha_z=0.1)


def _unit(rng, n, z_min=0.05):
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.maximum(abs(v[:, 2]), z_min)
    return v / np.linalg.norm(v, axis=1)[:, None]


@pytest.mark.parametrize("model", ["measured_psd2d_ssa", "measured_psd2d"])
def test_a_crossing_lay_map_gives_the_2d_psd_model(model):
    # Two lays 70° apart (correlation lengths 0.25 and 2 µm, 10 and 6 nm rms, on 20 µm): the
    # PSD is not constant on ellipses, so fit writes its 2-D table.
    dx = 20e-6 / 256
    lays = [_stretched_map(a, dx=dx, lx=0.25e-6, ly=2e-6, seed=s) * r for a, s, r in ((0.0, 5, 0.5), (70.0, 6, 0.3))]
    scan = lustre.Scan(lays[0] + lays[1], dx, dx, name="crossing")
    got = lustre.fit(scan, metal="cu")
    assert "map" in got["psd"], sorted(got["psd"])
    m = lustre.Material.from_fit(got, model=model)
    rng = np.random.default_rng(3)
    wi, wo = _unit(rng, 256), _unit(rng, 256)
    f, pdf = m.eval(wi, wo, 550.0)
    assert np.all(np.isfinite(f)) and np.all(f >= 0) and np.all(pdf >= 0)
    assert np.all(pdf[f > 0] > 0)
    # Reciprocity: the scattering term depends on wi, wo through ζ and cosines only.
    f_back, _ = m.eval(wo, wi, 550.0)
    np.testing.assert_allclose(f_back, f, rtol=1e-9, atol=0)
    # A sample's pdf and weight are those eval gives for its direction.
    wi_s = np.repeat([[math.sin(0.6), 0.0, math.cos(0.6)]], 512, axis=0)
    u = rng.uniform(size=(512, 3))
    u[:, 0] = 0.999 + 0.001 * u[:, 0]  # past the delta lobe's share (g ~ 0.1: p_δ ~ 0.9)
    wo_s, pdf_s, weight, is_delta = m.sample(wi_s, 550.0, u)
    glossy = ~is_delta & (pdf_s > 0)
    assert glossy.sum() > 100
    f_s, pdf_e = m.eval(wi_s[glossy], wo_s[glossy], 550.0)
    np.testing.assert_allclose(pdf_s[glossy], pdf_e, rtol=1e-9)
    np.testing.assert_allclose(weight[glossy], f_s * wo_s[glossy, 2] / pdf_e, rtol=1e-9)
    # The lays show: ζ along x and along y scatter differently.
    z = math.sqrt(1 - 0.02**2)
    along_x = m.eval([0, 0, 1], [0.02, 0.0, z], 550.0)[0][0]
    along_y = m.eval([0, 0, 1], [0.0, 0.02, z], 550.0)[0][0]
    assert abs(along_x / along_y - 1) > 0.05, (along_x, along_y)
    a = m.albedo([0.0, 45.0], 550.0)
    assert np.all((a > 0.3) & (a < 1.0)), a


@pytest.mark.parametrize("model", ["measured_psd2d_ssa", "measured_psd2d"])
def test_the_2d_psd_model_from_a_fit_file_equals_brdf_eval(cli, tmp_path, model):
    # corpus/mi-1 is flagged non-elliptical: `lustre fit` writes [psd.map] into the file.
    out = tmp_path / "mi1.toml"
    cli("fit", "data/surfaces/corpus/mi-1.mi", "--metal", "cu", "-o", str(out), "--no-plots")
    assert "[psd.map]" in out.read_text()
    keys = {"model": model, "include": str(out)}
    geometry = [(ti, to, po) for ti in (0.0, 40.0, 80.0) for to in (2.0, 30.0) for po in (180.0, 135.0, 90.0, 20.0)]
    lines = [
        json.dumps({"lambda_nm": 550.0, "theta_i_deg": ti, "theta_o_deg": to, "phi_o_deg": po, **keys})
        for ti, to, po in geometry
    ]
    want = loads_lines(cli("brdf", "eval", input="\n".join(lines) + "\n"))
    assert all("error" not in w for w in want), want[0]
    m = lustre.Material(**keys)
    wi = np.array([direction(ti, 0.0) for ti, _, _ in geometry])
    wo = np.array([direction(to, po) for _, to, po in geometry])
    f, pdf = m.eval(wi, wo, 550.0)
    assert [w["f"] for w in want] == list(f)
    assert [w["pdf"] for w in want] == list(pdf)
    assert max(f) > 0
