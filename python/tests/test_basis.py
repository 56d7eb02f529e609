"""eval_sh against scipy and the closed forms of docs/conventions.md."""
import math

import numpy as np
import pytest
from scipy.special import sph_harm

import shtool


def random_dirs(n, seed=0, dtype=np.float64):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(dtype)


def scipy_real_sh(order, dirs):
    """shtool's real SH from scipy's complex ones. Debian's scipy 1.10 takes
    sph_harm(m, l, azimuth, polar) and includes the Condon-Shortley phase, as shtool's
    P_l^m does, so y_l^m = sqrt2 Re Y_l^m (m > 0), Re Y_l^0 (m = 0) and
    sqrt2 Im Y_l^|m| (m < 0), with no further sign."""
    x, y, z = dirs.T
    polar = np.arccos(np.clip(z, -1, 1))
    azimuth = np.arctan2(y, x)
    out = np.empty((len(dirs), order * order))
    for l in range(order):
        for m in range(-l, l + 1):
            c = sph_harm(abs(m), l, azimuth, polar)
            i = l * (l + 1) + m
            out[:, i] = c.real if m == 0 else math.sqrt(2) * (c.real if m > 0 else c.imag)
    return out


def test_against_scipy_up_to_order_20():
    dirs = random_dirs(500)
    np.testing.assert_allclose(shtool.eval_sh(20, dirs), scipy_real_sh(20, dirs), rtol=0, atol=1e-13)


def test_closed_forms_bands_0_to_2():
    d = random_dirs(100, seed=1)
    x, y, z = d.T
    c0 = 1 / (2 * math.sqrt(math.pi))
    c1 = math.sqrt(3 / (4 * math.pi))
    c2 = math.sqrt(15 / (4 * math.pi))
    expected = np.stack([np.full_like(x, c0), -c1 * y, c1 * z, -c1 * x, c2 * x * y, -c2 * y * z,
                         math.sqrt(5 / (16 * math.pi)) * (3 * z * z - 1), -c2 * x * z,
                         math.sqrt(15 / (16 * math.pi)) * (x * x - y * y)], axis=1)
    np.testing.assert_allclose(shtool.eval_sh(3, d), expected, rtol=0, atol=1e-15)


def test_directions_are_normalised_and_batched(cli):
    dirs = np.array([[[0.3, -0.5, 0.8]], [[3.0, -5.0, 8.0]]])
    v = shtool.eval_sh(3, dirs)
    assert v.shape == (2, 1, 9)
    np.testing.assert_allclose(v[0], v[1], rtol=0, atol=1e-15)
    import json
    printed = json.loads(cli("eval", "--order", 3, "--dir", "0.3,-0.5,0.8"))["values"]
    np.testing.assert_array_equal(v[0, 0], printed)


def test_float32_stays_float32_and_out_is_written_in_place():
    d = random_dirs(10, dtype=np.float32)
    v = shtool.eval_sh(4, d)
    assert v.dtype == np.float32
    np.testing.assert_allclose(v, shtool.eval_sh(4, d.astype(np.float64)), atol=1e-6)
    out = np.empty((10, 16), np.float32)
    r = shtool.eval_sh(4, d, out=out)
    assert np.shares_memory(r, out)
    np.testing.assert_array_equal(out, v)


@pytest.mark.parametrize("bad, error", [
    (np.zeros((2, 3)), ValueError),               # zero direction
    (np.ones((2, 4)), ValueError),                # not (..., 3)
    (np.ones((2, 3), np.complex128), TypeError),  # dtype (integers are taken as float64)
    (np.array([[np.nan, 0, 1.0]]), ValueError),   # not finite
    (np.array([[1.0, np.nan, 0]]), ValueError),   # not finite after a finite largest component
    (np.array([[1.0, 0, np.nan]], np.float32), ValueError),
    (np.array([[0, 0, 1.0], [1.0, 0, -np.inf]]), ValueError),
])
def test_bad_directions(bad, error):
    with pytest.raises(error):
        shtool.eval_sh(3, bad)


def test_lists_are_float64():
    v = shtool.eval_sh(2, [0.0, 0.0, 2.0])
    assert v.dtype == np.float64 and v.shape == (4,)


def test_bad_orders():
    for order in (0, -1, 129):
        with pytest.raises(ValueError):
            shtool.eval_sh(order, np.ones((1, 3)))
