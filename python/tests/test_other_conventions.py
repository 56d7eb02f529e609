"""How other libraries' SH coefficients map onto shtool's (docs/python.md): each
library's basis transcribed from its source, against shtool.eval_sh."""
import math

import numpy as np
from scipy.spatial.transform import Rotation

import shtool


def dirs(n=200, seed=0):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def signs(order):
    """(-1)^m per flat index."""
    return np.array([(-1.0) ** (i - l * (l + 1)) for l in range(order) for i in range(l * l, (l + 1) ** 2)])


def gaussian_splatting_basis(d):
    """graphdeco-inria/gaussian-splatting utils/sh_utils.py eval_sh, degree 3, per coefficient."""
    C0, C1 = 0.28209479177387814, 0.4886025119029199
    C2 = [1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792, 0.5462742152960396]
    C3 = [-0.5900435899266435, 2.890611442640554, -0.4570457994644658, 0.3731763325901154, -0.4570457994644658,
          1.445305721320277, -0.5900435899266435]
    x, y, z = d.T
    xx, yy, zz = x * x, y * y, z * z
    return np.stack([np.full_like(x, C0), -C1 * y, C1 * z, -C1 * x,
                     C2[0] * x * y, C2[1] * y * z, C2[2] * (2 * zz - xx - yy), C2[3] * x * z, C2[4] * (xx - yy),
                     C3[0] * y * (3 * xx - yy), C3[1] * x * y * z, C3[2] * y * (4 * zz - xx - yy),
                     C3[3] * z * (2 * zz - 3 * xx - 3 * yy), C3[4] * x * (4 * zz - xx - yy),
                     C3[5] * z * (xx - yy), C3[6] * x * (xx - 3 * yy)], axis=1)


def test_gaussian_splatting_is_shtools_basis():
    d = dirs()
    np.testing.assert_allclose(gaussian_splatting_basis(d), shtool.eval_sh(4, d), atol=1e-15)


def three_get_at(coeffs, n):
    """three.js src/math/SphericalHarmonics3.js getAt (9 RGB coefficients, y-up normal)."""
    x, y, z = n.T
    basis = np.stack([np.full_like(x, 0.282095), 0.488603 * y, 0.488603 * z, 0.488603 * x, 1.092548 * x * y,
                      1.092548 * y * z, 0.315392 * (3 * z * z - 1), 1.092548 * x * z, 0.546274 * (x * x - y * y)], 1)
    return basis @ coeffs


# three.js's y-up frame: its vector (x, y, z) is shtool's (x, -z, y); n = Q w.
Q = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])


def test_three_js_coefficients():
    lighting = np.random.default_rng(1).normal(size=(9, 3))  # shtool, (N^2, RGB)
    three = signs(3)[:, None] * shtool.rotate(lighting, Q, axis=0)
    w = dirs()
    np.testing.assert_allclose(three_get_at(three, w @ Q.T), shtool.eval_sh(3, w) @ lighting, atol=2e-5)


def e3nn_integral(v):
    """e3nn o3/_spherical_harmonics.py for l <= 2, normalization='integral' (divided by sqrt(4 pi))."""
    x, y, z = v.T
    s3, s5, s15 = math.sqrt(3), math.sqrt(5), math.sqrt(15)
    sh = np.stack([np.ones_like(x), s3 * x, s3 * y, s3 * z, s15 * x * z, s15 * x * y,
                   s5 * (y * y - 0.5 * (x * x + z * z)), s15 * y * z, 0.5 * s15 * (z * z - x * x)], 1)
    return sh / math.sqrt(4 * math.pi)


def test_e3nn_integral_normalisation():
    # e3nn's vector (x, y, z) is shtool's (y, z, x), and e3nn has no Condon-Shortley phase.
    w = dirs()
    np.testing.assert_allclose(e3nn_integral(w[:, [1, 2, 0]]), shtool.eval_sh(3, w) * signs(3), atol=1e-15)


def test_rotations_agree_with_scipy_frames():
    # quat_to_matrix takes (w, x, y, z); scipy's from_quat takes (x, y, z, w).
    q = np.array([0.5, 0.5, -0.5, 0.5])
    np.testing.assert_allclose(shtool.quat_to_matrix(q), Rotation.from_quat(q[[1, 2, 3, 0]]).as_matrix(),
                               atol=1e-15)
