"""product, project_env, irradiance, window, light."""
import json
import math
import re

import numpy as np
import pytest

import shtool
from conftest import SOURCE_DIR
from gil import RELEASED_SHARE, gil_free_share


def sphere_quadrature(nodes):
    """Gauss-Legendre in cos(polar) x equispaced azimuth: exact for band-limited
    integrands of degree < 2 nodes."""
    z, wz = np.polynomial.legendre.leggauss(nodes)
    phi = 2 * np.pi * np.arange(2 * nodes) / (2 * nodes)
    s = np.sqrt(1 - z * z)
    dirs = np.stack([np.outer(s, np.cos(phi)), np.outer(s, np.sin(phi)), np.outer(z, np.ones_like(phi))], -1)
    weights = np.outer(wz, np.full(phi.shape, 2 * np.pi / len(phi)))
    return dirs.reshape(-1, 3), weights.ravel()


@pytest.mark.parametrize("method", ["auto", "tripling", "fourier", "grid"])
def test_product_against_quadrature(method):
    rng = np.random.default_rng(1)
    n = 5
    a, b = rng.normal(size=(2, 3, n * n))
    dirs, w = sphere_quadrature(3 * n)
    y = shtool.eval_sh(n, dirs)
    expected = ((y @ a.T) * (y @ b.T) * w[:, None]).T @ y  # (3, n^2)
    np.testing.assert_allclose(shtool.product(a, b, method=method), expected, atol=1e-12)


def test_product_of_other_orders_and_dtypes():
    rng = np.random.default_rng(2)
    a, b = rng.normal(size=9), rng.normal(size=16)
    dirs, w = sphere_quadrature(12)
    fa, fb = shtool.eval_sh(3, dirs) @ a, shtool.eval_sh(4, dirs) @ b
    expected = (fa * fb * w) @ shtool.eval_sh(5, dirs)
    np.testing.assert_allclose(shtool.product(a, b, order=5), expected, atol=1e-12)
    g = shtool.product(a.astype(np.float32), b.astype(np.float32))
    assert g.dtype == np.float32 and g.shape == (9,)
    with pytest.raises(TypeError):
        shtool.product(a, b.astype(np.float32))
    with pytest.raises(ValueError):
        shtool.product(a, b, method="magic")


def texel_integrals(width, height, order, nodes=24):
    """The integral of every y_i over every texel of a W x H equirect in shtool's mapping
    (polar [pi y/H, pi (y+1)/H], azimuth [pi - 2 pi (x+1)/W, pi - 2 pi x/W]): a
    Gauss-Legendre product rule per texel, (H, W, N^2)."""
    u, wu = np.polynomial.legendre.leggauss(nodes)
    out = np.zeros((height, width, order * order))
    for y in range(height):
        t0, t1 = np.pi * y / height, np.pi * (y + 1) / height
        t = (t0 + t1) / 2 + (t1 - t0) / 2 * u
        for x in range(width):
            p0, p1 = np.pi - 2 * np.pi * (x + 1) / width, np.pi - 2 * np.pi * x / width
            p = (p0 + p1) / 2 + (p1 - p0) / 2 * u
            tt, pp = np.meshgrid(t, p, indexing="ij")
            d = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], -1).reshape(-1, 3)
            w = (np.outer(wu, wu) * np.sin(tt)).ravel() * (t1 - t0) / 2 * (p1 - p0) / 2
            out[y, x] = w @ shtool.eval_sh(order, d)
    return out


def test_project_env_against_exact_texel_integrals():
    rng = np.random.default_rng(3)
    image = rng.uniform(size=(6, 12, 2)).astype(np.float32)
    c = shtool.project_env(image, 4)
    assert c.shape == (16, 2) and c.dtype == np.float64
    expected = np.einsum("hwi,hwc->ic", texel_integrals(12, 6, 4), image.astype(np.float64))
    np.testing.assert_allclose(c, expected, atol=1e-12)
    np.testing.assert_array_equal(shtool.project_env(image.astype(np.float64), 4), c)


def test_project_env_constant_cubemap_and_cross():
    faces = np.ones((6, 8, 8, 3), np.float32)
    c = shtool.project_env(faces, 3, layout="faces")
    np.testing.assert_allclose(c[0], math.sqrt(4 * math.pi), rtol=1e-12)
    np.testing.assert_allclose(c[1:], 0, atol=1e-12)
    cross = np.ones((24, 32, 3), np.float32)
    np.testing.assert_allclose(shtool.project_env(cross, 3, layout="cross"), c, atol=1e-12)


def test_project_env_file_equals_the_cli(cli, tmp_path):
    sky = SOURCE_DIR / "data" / "sky.hdr"
    cli("project-env", sky, "--order", 3, "--json", tmp_path / "cli.json", "--out", tmp_path / "cli.shtb",
        "--window", "auto")
    c = shtool.project_env_file(sky, order=3, json=tmp_path / "py.json", out=str(tmp_path / "py.shtb"), window="auto")
    assert (tmp_path / "py.shtb").read_bytes() == (tmp_path / "cli.shtb").read_bytes()
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "cli.json").read_bytes()
    np.testing.assert_array_equal(c, json.loads((tmp_path / "cli.json").read_text())["coefficients"])


def test_irradiance_and_window():
    c = np.arange(1, 17, dtype=np.float64)
    e = shtool.irradiance(c)
    a = [math.pi, 2 * math.pi / 3, math.pi / 4, 0.0]
    np.testing.assert_allclose(e, c * np.repeat(a, [1, 3, 5, 7]), atol=1e-15)
    h = shtool.window(c.astype(np.float32), "hann", cutoff=4)
    assert h.dtype == np.float32
    w = [1, 0.5 * (1 + math.cos(math.pi / 4)), 0.5, 0.5 * (1 + math.cos(3 * math.pi / 4))]
    np.testing.assert_allclose(h, c * np.repeat(w, [1, 3, 5, 7]), rtol=1e-6)
    rgb = shtool.light("cone", 6, direction=(0, 0, 1), half_angle=30)
    windowed, factors, cutoff = shtool.window(rgb, "auto", axis=0, return_factors=True)
    assert windowed.shape == rgb.shape and len(factors) == 6
    with pytest.raises(ValueError):
        shtool.window(c, "box")


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_irradiance_and_product_past_the_dtype_are_refused_not_returned_as_inf(dtype):
    # Irradiance multiplies band 0 by pi, a product squares: finite coefficients near the
    # largest float are refused naming the vector, as rotate refuses them; NaN in gives
    # NaN out, as numpy's arithmetic would.
    f = np.ones((3, 9), dtype)
    f[1, 0] = np.finfo(dtype).max / 2
    with pytest.raises(ValueError, match=r"irradiance of vector 1 overflows"):
        shtool.irradiance(f)
    with pytest.raises(ValueError, match=r"product of vector 1 overflows"):
        shtool.product(f, f)
    with pytest.raises(ValueError, match=r"product of vector 1 overflows"):
        shtool.product(f, np.full(9, 100, dtype))  # one vector for every row
    assert np.isfinite(shtool.window(f, "hann", cutoff=3)).all()
    f[1] = np.nan
    assert np.isnan(shtool.irradiance(f)[1]).all()
    assert np.isnan(shtool.product(f, f)[1]).all()
    assert np.isfinite(shtool.product(f, f)[[0, 2]]).all()


def test_light_equals_the_cli(cli, tmp_path):
    for args, kw in [(["--type", "cone", "--dir", "1,2,3", "--half-angle", 20, "--color", "1,0.5,0.25"],
                      dict(kind="cone", direction=(1, 2, 3), half_angle=20, color=(1, 0.5, 0.25))),
                     (["--type", "hemisphere", "--dir", "0,0,1", "--ground", "0.1,0.2,0.3"],
                      dict(kind="hemisphere", ground=(0.1, 0.2, 0.3)))]:
        cli("light", "--order", 4, *args, "--json", tmp_path / "l.json")
        printed = json.loads((tmp_path / "l.json").read_text())
        np.testing.assert_array_equal(shtool.light(order=4, **kw), printed["coefficients"])
    with pytest.raises(ValueError):
        shtool.light("cone", 3)  # no half-angle
    with pytest.raises(ValueError):
        shtool.light("laser", 3)


@pytest.mark.parametrize("image, kw", [
    (np.ones((5, 12, 3), np.float32), {}),                       # not 2:1
    (np.ones((4, 8, 3), np.float32), {"window": "magic"}),
    (np.full((4, 8, 3), np.nan, np.float32), {}),               # non-finite texel
    (np.ones((4, 8), np.float32), {}),                          # no channel axis
    (np.ones((4, 8, 3), np.float32), {"order": 40}),
])
def test_project_env_bad_input(image, kw):
    order = kw.pop("order", 3)
    with pytest.raises(ValueError):
        shtool.project_env(image, order, **kw)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_project_env_names_a_bad_texel_by_its_numpy_index(dtype):
    # As numpy addresses it, [row, column, channel], whatever the problem (the CLI's
    # images say texel (x, y), the column first).
    for value, what in ((np.nan, "is NaN"), (np.inf, "is infinite")):
        img = np.ones((4, 8, 3), dtype)
        img[2, 3, 1] = value
        with pytest.raises(ValueError, match=re.escape("image[2, 3, 1] " + what)):
            shtool.project_env(img, 3)
    if dtype == np.float64:
        img = np.ones((4, 8, 3), dtype)
        img[2, 3, 1] = 1e39
        with pytest.raises(ValueError, match=re.escape("image[2, 3, 1] = 1e+39 is beyond float32's range")):
            shtool.project_env(img, 3)


@pytest.mark.parametrize("call", [
    lambda c: shtool.irradiance(c, threads=1),
    lambda c: shtool.window(c, "hann", threads=1),
])
def test_irradiance_and_window_release_the_gil(call):
    c = np.random.default_rng(5).normal(size=(40_000, 256))
    share, _ = gil_free_share(lambda: call(c))
    assert share > RELEASED_SHARE


def test_irradiance_and_window_in_chunks_equal_one_call():
    c = np.random.default_rng(6).normal(size=(9000, 16)).astype(np.float32)
    for threads in (1, 2, 0):
        np.testing.assert_array_equal(shtool.irradiance(c, threads=threads),
                                      np.concatenate([shtool.irradiance(c[k:k + 10]) for k in range(0, 9000, 10)]))
        np.testing.assert_array_equal(shtool.window(c, "lanczos", threads=threads),
                                      np.concatenate([shtool.window(c[k:k + 10], "lanczos") for k in
                                                      range(0, 9000, 10)]))


def test_project_env_channels_are_1_to_4():
    for channels in (1, 4):
        assert shtool.project_env(np.ones((4, 8, channels), np.float32), 2).shape == (4, channels)
    with pytest.raises(ValueError, match="image has 5 channels; 1 to 4 supported"):
        shtool.project_env(np.ones((4, 8, 5), np.float32), 2)
    with pytest.raises(ValueError, match="image has 6 channels; 1 to 4 supported"):
        shtool.project_env(np.ones((6, 4, 4, 6), np.float32), 2, layout="faces")


def test_project_env_float64_beyond_float32():
    image = np.ones((4, 8, 2))
    image[1, 3, 1] = -1e39
    with pytest.raises(ValueError, match=r"image\[1, 3, 1\] = -1e\+39.* beyond float32's range"):
        shtool.project_env(image, 2)
    image[1, 3, 1] = np.inf  # infinite as given: the projection's own message
    with pytest.raises(ValueError, match="infinite"):
        shtool.project_env(image, 2)
    # float64 texels are rounded to float32, as a file's are.
    image = np.random.default_rng(7).uniform(size=(4, 8, 3))
    np.testing.assert_array_equal(shtool.project_env(image, 3), shtool.project_env(image.astype(np.float32), 3))
