"""rotate: g(w) = f(R^-1 w), checked as f(w) == rotate(f, R)(R w)."""
import json
import os
import subprocess
import sys
import threading

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import shtool
from conftest import SOURCE_DIR
from gil import RELEASED_SHARE, gil_free_share

# Largest error allowed per unit of the coefficients' size: the methods' default
# tolerance (1e-10 double, 1e-6 float) plus rounding over up to 144 coefficients.
TOL = {np.float64: 1e-9, np.float32: 2e-4}


def random_rotation(seed):
    return Rotation.random(random_state=seed).as_matrix()


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("order", range(1, 13))
def test_rotated_function_at_rotated_direction(order, dtype):
    rng = np.random.default_rng(order)
    f = rng.normal(size=(4, order * order)).astype(dtype)
    r = random_rotation(order)
    g = shtool.rotate(f, r)
    assert g.dtype == dtype and g.shape == f.shape
    w = rng.normal(size=(64, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    before = shtool.eval_sh(order, w) @ f.astype(np.float64).T
    after = shtool.eval_sh(order, w @ r.T) @ g.astype(np.float64).T
    scale = np.abs(before).max() + 1
    np.testing.assert_allclose(after, before, rtol=0, atol=TOL[dtype] * scale)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_composition_and_identity(dtype):
    f = np.random.default_rng(3).normal(size=(10, 36)).astype(dtype)
    r1, r2 = random_rotation(1), random_rotation(2)
    both = shtool.rotate(shtool.rotate(f, r1), r2)
    np.testing.assert_allclose(both, shtool.rotate(f, r2 @ r1), atol=TOL[dtype] * 10)
    np.testing.assert_allclose(shtool.rotate(f, np.eye(3)), f, atol=TOL[dtype])


def test_methods_agree_and_match_the_cli(cli):
    f = np.random.default_rng(4).normal(size=25)
    q = np.array([0.8, 0.2, -0.4, 0.4])
    q /= np.linalg.norm(q)
    r = shtool.quat_to_matrix(q)
    # The Taylor methods hold for small tilts only.
    for method in ("reference", "zxzxz", "auto", "zhf", "zhf-tailored"):
        np.testing.assert_allclose(shtool.rotate(f, r, method=method), shtool.rotate(f, r, method="reference"),
                                   atol=1e-9)
    for method in ("reference", "zxzxz", "zhf", "zhf-tailored"):
        printed = json.loads(cli("rotate", "--order", 5, "--method", method, "--matrix",
                                 ",".join(repr(float(x)) for x in r.ravel()),
                                 "--coeffs", ",".join(repr(float(x)) for x in f)))
        np.testing.assert_array_equal(shtool.rotate(f, r, method=method), printed["coefficients"])


def test_quaternion_matches_scipy():
    q = np.random.default_rng(5).normal(size=(7, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    expected = Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()  # scipy: (x, y, z, w)
    np.testing.assert_allclose(shtool.quat_to_matrix(q), expected, atol=1e-15)
    assert shtool.quat_to_matrix(q.astype(np.float32)).dtype == np.float32


def test_axis_and_rgb_lighting():
    lighting = np.random.default_rng(6).normal(size=(16, 3))  # (N^2, 3): coefficients on axis 0
    r = random_rotation(6)
    g = shtool.rotate(lighting, r, axis=0)
    assert g.shape == (16, 3)
    np.testing.assert_allclose(g, shtool.rotate(lighting.T.copy(), r).T, atol=0)


def test_one_matrix_per_vector_batch():
    rng = np.random.default_rng(7)
    f = rng.normal(size=(5, 3, 9))  # 5 splats, RGB, order 3
    rs = np.stack([random_rotation(s) for s in range(5)])
    g = shtool.rotate(f, rs)
    for k in range(5):
        np.testing.assert_allclose(g[k], shtool.rotate(f[k], rs[k]), atol=1e-12)


def test_no_copy_with_out_and_contiguous_input():
    f = np.random.default_rng(8).normal(size=(1000, 16))
    out = np.empty_like(f)
    g = shtool.rotate(f, random_rotation(8), out=out)
    assert np.shares_memory(g, out)
    with pytest.raises(ValueError):
        shtool.rotate(f, random_rotation(8), out=f)  # in place would alias the kernel's input
    with pytest.raises(TypeError):
        shtool.rotate(f, random_rotation(8), out=np.empty((1000, 16), np.float32))


def test_two_threads_at_once_give_the_results_of_one():
    rng = np.random.default_rng(9)
    data = [rng.normal(size=(20000, 3, 16)).astype(np.float32) for _ in range(2)]
    rs = [random_rotation(10), random_rotation(11)]
    alone = [shtool.rotate(d, r) for d, r in zip(data, rs)]
    results = [None, None]

    def work(k):
        for _ in range(3):
            results[k] = shtool.rotate(data[k], rs[k])

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k in range(2):
        np.testing.assert_array_equal(results[k], alone[k])


@pytest.mark.parametrize("matrix", [
    np.diag([1.0, 1.0, -1.0]),          # reflection
    np.eye(3) * 2,                      # not orthonormal
    np.eye(4),                          # shape
    np.full((3, 3), np.nan),            # not finite
])
def test_bad_matrices(matrix):
    with pytest.raises(ValueError):
        shtool.rotate(np.ones(9), matrix)


def test_bad_inputs():
    with pytest.raises(ValueError):
        shtool.rotate(np.ones(8), np.eye(3))            # not N^2
    with pytest.raises(ValueError):
        shtool.rotate(np.ones(9), np.eye(3), method="fast")
    with pytest.raises(TypeError):
        shtool.rotate(np.ones(9, np.int32), np.eye(3))
    with pytest.raises(TypeError):
        shtool.rotate(np.ones(9, np.float16), np.eye(3))
    with pytest.raises(ValueError):
        shtool.rotate(np.ones(9), np.eye(3), axis=3)
    with pytest.raises(ValueError):
        shtool.quat_to_matrix([1.0, 1.0, 0, 0])          # not unit
    with pytest.raises(ValueError):
        shtool.rotate(np.ones((2, 9)), np.stack([np.eye(3)] * 3))  # 3 matrices for 2 vectors


@pytest.mark.parametrize("method", ["auto", "zxzxz", "zhf"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_rotation_past_the_dtype_is_refused_not_returned_as_inf(method, dtype):
    # Finite coefficients near the largest float the rotation's steps take past it: once
    # returned as inf and NaN, now refused as the CLI refuses them, naming the vector.
    big = np.finfo(dtype).max
    f = np.ones((3, 16), dtype)
    f[1] = big
    with pytest.raises(ValueError, match=r"rotation of vector 1 overflows"):
        shtool.rotate(f, np.eye(3), method=method)
    with pytest.raises(ValueError, match=r"rotation of vector 1 overflows"):
        shtool.rotate(f, np.stack([np.eye(3)] * 3))
    # NaN in gives NaN out, as numpy's arithmetic would.
    f[1] = np.nan
    assert np.isnan(shtool.rotate(f, np.eye(3), method=method)[1]).all()


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_one_bad_matrix_in_a_batch_is_named(dtype):
    rs = np.stack([np.eye(3)] * 5 + [np.diag([1.0, 1.0, -1.0])]).astype(dtype)
    with pytest.raises(ValueError, match=r"matrix\[5\]"):
        shtool.rotate(np.ones((6, 9), dtype), rs)


def test_the_gil_is_released_during_a_long_call():
    f = np.random.default_rng(12).normal(size=(400_000, 64))
    share, _ = gil_free_share(lambda: shtool.rotate(f, random_rotation(12), threads=1), 1)
    assert share > RELEASED_SHARE


def test_a_call_holding_the_gil_is_caught():
    # The measure itself: sorting a list of ints holds the GIL throughout (no bytecode
    # runs while it compares), so the share left to the measuring thread is far below the
    # bound: under 1 % on a quiet machine, 2.6 % once during a whole CI run on 2 cores.
    values = np.random.default_rng(17).permutation(1_000_000).tolist()
    share, took = gil_free_share(lambda: sorted(values))
    assert took > 0.1 and share < RELEASED_SHARE / 2


def test_empty_batches():
    assert shtool.rotate(np.zeros((0, 9)), np.eye(3)).shape == (0, 9)
    assert shtool.rotate(np.zeros((0, 9)), np.zeros((0, 3, 3))).shape == (0, 9)
    assert shtool.eval_sh(3, np.zeros((0, 3))).shape == (0, 9)
    assert shtool.product(np.ones(9), np.ones((0, 9))).shape == (0, 9)


def test_orders_above_the_shipped_helpers_table(cli):
    # The shipped rotation-helpers table covers order 30: above it the default method
    # computes the helpers (the CLI as well), it does not refuse.
    f = np.random.default_rng(13).normal(size=31 * 31)
    r = random_rotation(13)
    reference = shtool.rotate(f, r, method="reference")
    for method in ("auto", "zxzxz"):
        np.testing.assert_allclose(shtool.rotate(f, r, method=method), reference, atol=1e-9 * np.abs(f).max())
    printed = json.loads(cli("rotate", "--order", 31, "--method", "zxzxz", "--matrix",
                             ",".join(repr(float(x)) for x in r.ravel()),
                             "--coeffs", ",".join(repr(float(x)) for x in f)))
    np.testing.assert_array_equal(printed["coefficients"], shtool.rotate(f, r, method="zxzxz"))


def test_helpers_are_built_with_the_gil_released():
    # Order 37's helpers are made by the first call (about a second): not with the GIL held.
    f = np.ones(37 * 37)
    share, took = gil_free_share(lambda: shtool.rotate(f, np.eye(3), method="zxzxz", threads=1), 1)
    assert took > 0.2 and share > RELEASED_SHARE


def test_a_given_helpers_table_must_cover_the_order(tmp_path):
    shtool.gen_tensors(3, str(tmp_path), what=["rotation"])
    table = tmp_path / "rotation-helpers.shtb"
    f = np.random.default_rng(14).normal(size=(2, 9))
    r = random_rotation(14)
    np.testing.assert_allclose(shtool.rotate(f, r, method="zxzxz", tables=table), shtool.rotate(f, r), atol=1e-12)
    with pytest.raises(ValueError, match="covers order 3"):
        shtool.rotate(np.ones(16), r, method="zxzxz", tables=table)
    (tmp_path / "bad.shtb").write_bytes(table.read_bytes()[:-9])
    with pytest.raises(ValueError, match="bad.shtb"):
        shtool.rotate(np.ones(9), r, method="zxzxz", tables=tmp_path / "bad.shtb")


def test_a_shipped_helpers_table_of_fewer_bands_is_no_error_a_damaged_one_is(tmp_path):
    # SHTOOL_TABLES naming a folder whose rotation-helpers table covers order 3: order 5
    # is computed. The same table cut short: a ValueError naming it.
    shtool.gen_tensors(3, str(tmp_path / "short"), what=["rotation"])
    (tmp_path / "damaged").mkdir()
    (tmp_path / "damaged" / "rotation-helpers.shtb").write_bytes(
        (tmp_path / "short" / "rotation-helpers.shtb").read_bytes()[:-9])
    code = ("import numpy as np, shtool\n"
            "f, r = np.arange(25.0), shtool.quat_to_matrix([0.8, 0.6, 0.0, 0.0])\n"
            "try:\n"
            "    g = shtool.rotate(f, r, method='zxzxz')\n"
            "    print(np.abs(g - shtool.rotate(f, r, method='reference')).max() < 1e-12)\n"
            "except ValueError as e:\n"
            "    print(e)\n")
    for folder, printed in (("short", "True"), ("damaged", str(tmp_path / "damaged" / "rotation-helpers.shtb"))):
        env = dict(os.environ, SHTOOL_TABLES=str(tmp_path / folder))
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
        assert r.returncode == 0 and printed in r.stdout, r.stdout + r.stderr


def test_zhf_finds_the_shipped_tables_without_shtool_tables(tmp_path):
    # From the build tree (or an install) with no SHTOOL_TABLES: the package's own tables.
    env = {k: v for k, v in os.environ.items() if k != "SHTOOL_TABLES"}
    code = ("import numpy as np, shtool\n"
            "f = np.random.default_rng(1).normal(size=100)\n"
            "r = shtool.quat_to_matrix([0.8, 0.2, -0.4, 0.4] / np.linalg.norm([0.8, 0.2, -0.4, 0.4]))\n"
            "for m in ('zhf', 'zhf-tailored'):\n"
            "    g = shtool.rotate(f, r, method='reference')\n"
            "    assert np.allclose(shtool.rotate(f, r, method=m), g, atol=1e-10)\n"
            "print('ok')\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert r.returncode == 0 and r.stdout == "ok\n", r.stderr


def test_zhf_orders_and_the_tables_keyword():
    f = np.random.default_rng(15).normal(size=(3, 100))
    r = random_rotation(15)
    reference = shtool.rotate(f, r, method="reference")
    for order in (1, 2, 3, 10):
        n2 = order * order
        np.testing.assert_allclose(shtool.rotate(f[:, :n2], r, method="zhf"), reference[:, :n2], atol=1e-10)
    with pytest.raises(ValueError, match="orders 1 to 10") as e:
        shtool.rotate(np.ones(121), r, method="zhf")
    assert "tables=" in str(e.value) and "--tables" not in str(e.value)
    table = SOURCE_DIR / "tables" / "zhf-shared-N10.shtb"
    for given in (table, str(table), os.fsencode(table)):
        np.testing.assert_allclose(shtool.rotate(f[:, :36], r, method="zhf", tables=given), reference[:, :36],
                                   atol=1e-10)
    with pytest.raises(ValueError):
        shtool.rotate(np.ones(121), r, method="zhf", tables=table)  # the table has 10 bands


@pytest.mark.parametrize("method", ["zhf", "zhf-tailored", "reference", "auto"])
def test_tol_is_checked_for_every_method(method):
    for tol in (-1.0, 0.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="tol"):
            shtool.rotate(np.ones(16), np.eye(3), method=method, tol=tol)


def test_quat_to_matrix_releases_the_gil():
    q = np.random.default_rng(16).normal(size=(2_000_000, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    share, _ = gil_free_share(lambda: shtool.quat_to_matrix(q, threads=1))
    assert share > RELEASED_SHARE


def test_quat_to_matrix_names_the_first_bad_quaternion():
    q = np.tile([1.0, 0, 0, 0], (10_000, 1))
    q[9000] = (1, 1, 0, 0)
    q[5000] = (0, 0, 0, 0)
    for threads in (1, 2):
        with pytest.raises(ValueError, match=r"q\[5000\]"):
            shtool.quat_to_matrix(q, threads=threads)
    np.testing.assert_array_equal(shtool.quat_to_matrix(q[:5000], threads=2), np.tile(np.eye(3), (5000, 1, 1)))
