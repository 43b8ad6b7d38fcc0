"""render(): the scene file and the same scene as a dict give the same image."""

import tomllib

import numpy as np
import pytest

import lustre



def small_scene(path):
    with open(path, "rb") as f:
        d = tomllib.load(f)
    d["camera"]["resolution"] = [24, 16]
    return d


def test_dict_and_file_render_alike(tmp_path):
    d = small_scene("scenes/default.toml")
    img = lustre.render(d, spp=2, seed=7, base_dir="scenes")
    assert img.shape == (16, 24, 3) and img.dtype == np.float32
    assert np.all(np.isfinite(img)) and img.max() > 0
    again = lustre.render(d, spp=2, seed=7, base_dir="scenes")
    np.testing.assert_array_equal(img, again)


def test_a_scene_file_renders_at_its_resolution():
    img = lustre.render("scenes/default.toml", spp=1, threads=2)
    assert img.shape == (240, 320, 3) and np.all(np.isfinite(img))


def test_render_errors():
    with pytest.raises(OSError, match="missing.toml"):
        lustre.render("missing.toml")
    with pytest.raises(ValueError, match="spp"):
        lustre.render(small_scene("scenes/default.toml"), spp=0, base_dir="scenes")


def test_spectral_bands_as_the_cli_writes_them():
    d = small_scene("scenes/default.toml")
    rgb, bands, bounds = lustre.render(d, spp=2, seed=7, base_dir="scenes", spectral=12)
    assert rgb.shape == (16, 24, 3) and bands.shape == (16, 24, 12)
    assert bands.dtype == np.float64 and np.all(np.isfinite(bands)) and np.all(bands >= 0)
    assert bands.max() > 0
    np.testing.assert_allclose(bounds, np.linspace(360.0, 830.0, 13), rtol=1e-12)
    # Bands are a deterministic function of the scene, seed and spp, like the image.
    _, again, _ = lustre.render(d, spp=2, seed=7, base_dir="scenes", spectral=12)
    np.testing.assert_array_equal(bands, again)
    for bad in (0, 257):
        with pytest.raises(ValueError, match="spectral"):
            lustre.render(d, spp=1, base_dir="scenes", spectral=bad)
