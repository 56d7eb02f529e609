"""Arguments as every call checks them: threads= whatever the batch size, messages that
name the Python keywords (not the CLI's options), byte order, wrong types."""
import numpy as np
import pytest

import shtool
from conftest import SOURCE_DIR

SMALL = {
    "eval_sh": lambda **kw: shtool.eval_sh(2, np.ones((10, 3)), **kw),
    "rotate": lambda **kw: shtool.rotate(np.ones((10, 9)), np.eye(3), **kw),
    "rotate_batch": lambda **kw: shtool.rotate(np.ones((10, 9)), np.tile(np.eye(3), (10, 1, 1)), **kw),
    "product": lambda **kw: shtool.product(np.ones(9), np.ones(9), **kw),
    "quat_to_matrix": lambda **kw: shtool.quat_to_matrix([1.0, 0, 0, 0], **kw),
    "irradiance": lambda **kw: shtool.irradiance(np.ones(9), **kw),
    "window": lambda **kw: shtool.window(np.ones(9), "hann", **kw),
    "project_env": lambda **kw: shtool.project_env(np.ones((4, 8, 3), np.float32), 2, **kw),
    "fit_zh": lambda **kw: shtool.fit_zh(np.ones((2, 9)), lobes=1, **kw),
    "fit_zh_mesh": lambda **kw: shtool.fit_zh_mesh(SOURCE_DIR / "data" / "spot.obj", order=2, lobes=1, rays=8, **kw),
    "project_env_file": lambda **kw: shtool.project_env_file(SOURCE_DIR / "data" / "sky.hdr", **kw),
    "search_lobes": lambda **kw: shtool.search_lobes(bands=[2], population=20, stall=2, restarts=1, **kw),
}


@pytest.mark.parametrize("name", sorted(SMALL))
def test_threads_is_checked_for_every_call(name):
    call = SMALL[name]
    with pytest.raises(ValueError, match=r"threads=100000 is more than this machine can use") as e:
        call(threads=100000)
    assert "--" not in str(e.value)
    with pytest.raises(ValueError, match=r"threads=-1") as e:
        call(threads=-1)
    assert "--" not in str(e.value)
    call(threads=1)


@pytest.mark.parametrize("call, words", [
    (lambda: shtool.fit_zh(np.ones((2, 9)), lobes=0), ["lobes"]),
    (lambda: shtool.fit_zh(np.ones((2, 9)), effort=9), ["effort"]),
    (lambda: shtool.light("cone", 3), ["light('cone') needs half_angle= (degrees)"]),
    (lambda: shtool.light("directional", 3, half_angle=10), ["half_angle= is for the cone and sphere"]),
    (lambda: shtool.gen_tensors(0, "unused"), ["order=0"]),
    (lambda: shtool.search_lobes(shared=True), ["shared", "order"]),
    (lambda: shtool.transform_splats(SOURCE_DIR / "data" / "spot.obj", "o.ply", quat=(0, 0, 0, 0)), ["quaternion"]),
    (lambda: shtool.project_env_file(SOURCE_DIR / "data" / "sky.hdr", cutoff=2), ["cutoff", "window"]),
])
def test_messages_name_the_python_keywords(call, words):
    with pytest.raises(ValueError) as e:
        call()
    assert "--" not in str(e.value)
    for word in words:
        assert word in str(e.value)


@pytest.mark.parametrize("dtype", [">f8", ">f4"])
def test_big_endian_arrays_are_converted(dtype):
    rng = np.random.default_rng(1)
    dirs, coeffs = rng.normal(size=(20, 3)), rng.normal(size=(20, 16))
    native = np.dtype(dtype).newbyteorder("=").type
    swapped = [a.astype(dtype) for a in (dirs, coeffs)]
    d, c = [a.astype(native) for a in (dirs, coeffs)]
    r = shtool.quat_to_matrix([0.8, 0.6, 0.0, 0.0])
    got = shtool.eval_sh(4, swapped[0])
    assert got.dtype == native and got.dtype.isnative
    np.testing.assert_array_equal(got, shtool.eval_sh(4, d))
    np.testing.assert_array_equal(shtool.rotate(swapped[1], r), shtool.rotate(c, r))
    np.testing.assert_array_equal(shtool.product(swapped[1], swapped[1]), shtool.product(c, c))
    np.testing.assert_array_equal(shtool.irradiance(swapped[1]), shtool.irradiance(c))
    np.testing.assert_array_equal(shtool.window(swapped[1], "hann"), shtool.window(c, "hann"))
    np.testing.assert_array_equal(shtool.quat_to_matrix(np.array([0.8, 0.6, 0, 0], dtype)),
                                  shtool.quat_to_matrix(np.array([0.8, 0.6, 0, 0], native)))
    image = rng.uniform(size=(4, 8, 3))
    np.testing.assert_array_equal(shtool.project_env(image.astype(dtype), 3),
                                  shtool.project_env(image.astype(native), 3))
    np.testing.assert_array_equal(shtool.fit_zh(swapped[1][:2], lobes=1, effort=1).axes,
                                  shtool.fit_zh(c[:2], lobes=1, effort=1).axes)


@pytest.mark.parametrize("call, message", [
    (lambda: shtool.rotate(np.ones(9), np.eye(3), method=3), "rotate: method must be a str, got int"),
    (lambda: shtool.rotate(np.ones(9), np.eye(3), tol="x"), "rotate: tol must be a number or None, got str"),
    (lambda: shtool.rotate(np.ones(9), np.eye(3), threads=1.5), "rotate: threads must be an int, got float"),
    (lambda: shtool.irradiance(np.ones(9), "n"), "axis must be an int, got str"),
    (lambda: shtool.window(np.ones(9), 5), "window: kind must be a str, got int"),
    (lambda: shtool.eval_sh("2", np.ones(3)), "eval_sh: order must be an int, got str"),
    (lambda: shtool.product(np.ones(9), np.ones(9), order="3"), "product: order must be an int or None, got str"),
    (lambda: shtool.project_env(np.ones((8, 16, 3), np.float32), 3, mirror_x="yes"),
     "project_env: mirror_x must be a bool, got str"),
    (lambda: shtool.fit_zh(np.ones(36), lobes="4"), "fit_zh: lobes must be an int, got str"),
])
def test_scalar_arguments_of_the_wrong_type_are_named(call, message):
    # Not pybind11's list of signatures: the argument, what it must be and what it was.
    with pytest.raises(TypeError) as e:
        call()
    assert str(e.value) == message


def test_numpy_scalars_pass_where_python_ones_do():
    c = np.arange(9.0)
    want = shtool.rotate(c, np.eye(3), tol=1e-6, threads=1)
    got = shtool.rotate(c, np.eye(3), tol=np.float32(1e-6), threads=np.int64(1))
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("call", [
    lambda: shtool.eval_sh(2, "up"),
    lambda: shtool.rotate(np.ones(9), np.eye(3), tables=3),
    lambda: shtool.load_table(None),
    lambda: shtool.fit_zh(np.ones((2, 9), np.int32)),
    lambda: shtool.transform_splat_arrays(positions=np.array([["a", "b", "c"]]), quaternion=(1, 0, 0, 0)),
    lambda: shtool.transform_splat_arrays(positions=np.ones((1, 3)), scale="2"),
])
def test_wrong_types_are_type_errors(call):
    with pytest.raises(TypeError):
        call()


@pytest.mark.parametrize("call, message", [
    (lambda: shtool.eval_sh(True, np.ones((1, 3))), "eval_sh: order must be an int, got bool"),
    (lambda: shtool.product(np.ones(9), np.ones(9), order=np.True_), "product: order must be an int, got bool"),
    (lambda: shtool.rotate(np.ones(9), np.eye(3), threads=True), "rotate: threads must be an int, got bool"),
    (lambda: shtool.rotate(np.ones(9), np.eye(3), tol=True), "rotate: tol cannot be a bool, got True"),
    (lambda: shtool.fit_zh(np.ones((1, 9)), lobes=True), "fit_zh: lobes must be an int, got bool"),
    (lambda: shtool.light("directional", True), "light: order must be an int, got bool"),
    (lambda: shtool.gen_tensors(True, "unused"), "gen_tensors: order must be an int, got bool"),
])
def test_bools_are_refused_where_the_parameter_is_not_one(call, message):
    # True is an int to Python and to pybind11: order=True would be an order-1 call.
    with pytest.raises(TypeError) as e:
        call()
    assert str(e.value) == message


def test_bools_pass_where_the_parameter_is_one():
    r, factors, cutoff = shtool.window(np.ones(9), "hann", return_factors=True)
    assert r.shape == (9,) and factors.shape == (3,)
    assert shtool.fit_zh(np.ones((1, 9)), lobes=1, direct=False).axes.shape == (1, 1, 3)


@pytest.mark.parametrize("call, message", [
    (lambda: shtool.eval_sh(2**31, np.ones((1, 3))), "eval_sh: order = 2147483648 is out of range"),
    (lambda: shtool.eval_sh(2, np.ones((1, 3)), threads=2**40), "eval_sh: threads = 1099511627776 is out of range"),
    (lambda: shtool.light("directional", -2**31 - 1), "light: order = -2147483649 is out of range"),
    (lambda: shtool.fit_zh(np.ones((1, 9)), seed=-1), "fit_zh: seed = -1 is out of range"),
])
def test_integers_past_their_c_type_are_value_errors(call, message):
    with pytest.raises(ValueError) as e:
        call()
    assert str(e.value) == message


@pytest.mark.parametrize("call, message", [
    (lambda: shtool.rotate(np.ones(9), np.eye(3, dtype=complex)), "matrix must be an array of real numbers, got dtype complex128"),
    (lambda: shtool.rotate(np.ones(9), "eye"), "matrix must be an array of real numbers, got str"),
    (lambda: shtool.light("directional", 3, direction="up"), "direction must be an array of real numbers, got str"),
    (lambda: shtool.light("directional", 3, color=(1j, 1, 1)), "color must be an array of real numbers, got dtype complex128"),
])
def test_arrays_of_complex_numbers_or_text_are_type_errors(call, message):
    # numpy would take a complex array's real part, with only a warning.
    with pytest.raises(TypeError) as e:
        call()
    assert str(e.value) == message
    # Integer arrays are numbers.
    np.testing.assert_array_equal(shtool.rotate(np.arange(9.0), np.eye(3, dtype=int)),
                                  shtool.rotate(np.arange(9.0), np.eye(3)))


@pytest.mark.parametrize("bands, message", [
    ("1-200", "bands: need 1 <= a <= b < 128, got '1-200'"),
    ("1-2000000000", "bands: need 1 <= a <= b < 128, got '1-2000000000'"),
    ([1, 200], "band 200: bands are 1..127"),
])
def test_search_lobes_checks_every_band_before_searching(bands, message):
    # At once: the first band's search would take a second, band 200's table gigabytes.
    with pytest.raises(ValueError) as e:
        shtool.search_lobes(bands=bands)
    assert str(e.value) == message


def test_window_auto_needs_a_vector():
    with pytest.raises(ValueError, match="coeffs holds no vector"):
        shtool.window(np.zeros((0, 9)), "auto")
    assert shtool.window(np.zeros((0, 9)), "hann").shape == (0, 9)


def test_paths_that_are_not_utf8_reach_the_file_system_as_their_bytes(tmp_path):
    out = bytes(tmp_path) + b"/t\xff.shtb"
    shtool.fit_zh_mesh(SOURCE_DIR / "data" / "spot.obj", out=out, order=2, lobes=1, rays=8)
    assert (b"t\xff.shtb",) == tuple(p for p in __import__("os").listdir(bytes(tmp_path)))
    by_bytes, by_str = shtool.load_table(out), shtool.load_table(__import__("os").fsdecode(out))
    assert by_bytes.kind == by_str.kind == "zh-fit"
    with pytest.raises(FileNotFoundError):
        shtool.load_table(bytes(tmp_path) + b"/none\xfe.shtb")
    written = shtool.gen_tensors(2, bytes(tmp_path) + b"/tables\xfe", what="rotation")
    assert written and all(__import__("os").path.exists(p) for p in written)
    assert all("\udcfe" in p for p in written)  # os.fsdecode's str, the same file passed back


def test_job_warnings_are_python_warnings(tmp_path):
    from test_fit_tables import write_splats
    write_splats(tmp_path / "in.ply")
    with pytest.warns(RuntimeWarning, match=r"sh_bits= does nothing here") as record:
        r = shtool.transform_splats(tmp_path / "in.ply", tmp_path / "out.glb", sh_bits=(3, 2))
    assert any("sh_bits= does nothing here" in w for w in r["warnings"])
    assert all("--" not in str(w.message) for w in record)


def test_rotate_tables_that_do_not_exist_raise_file_not_found():
    for method in ("auto", "zhf", "zxzxz"):
        with pytest.raises(FileNotFoundError, match="tables"):
            shtool.rotate(np.zeros(16), np.eye(3), method=method, tables="no-such-table.shtb")
    # The reference method reads no table, as `shtool rotate --method reference`.
    shtool.rotate(np.zeros(16), np.eye(3), method="reference", tables="no-such-table.shtb")


def test_transform_splat_arrays_checks_what_the_job_checks():
    with pytest.raises(ValueError, match="positions overflow float32 after the transform"):
        shtool.transform_splat_arrays(positions=np.full((3, 3), 3e38, np.float32), scale=10)
    with pytest.raises(ValueError, match="different numbers of splats: positions 3, rotations 5"):
        shtool.transform_splat_arrays(positions=np.zeros((3, 3)), rotations=np.tile([1.0, 0, 0, 0], (5, 1)))
    with pytest.raises(TypeError, match="positions must be an array of numbers, got bool"):
        shtool.transform_splat_arrays(positions=np.zeros((3, 3), bool))


def test_integer_directions_and_quaternions_are_taken_as_float64():
    assert np.array_equal(shtool.eval_sh(3, np.array([[0, 0, 1]])), shtool.eval_sh(3, np.array([[0.0, 0, 1]])))
    assert np.array_equal(shtool.quat_to_matrix(np.array([1, 0, 0, 0])), np.eye(3))
    with pytest.raises(TypeError, match="image must be an array of numbers, got None"):
        shtool.project_env(None, 3)


def test_project_env_names_the_layout_a_face_array_needs(tmp_path):
    with pytest.raises(ValueError, match=r'six cube faces: pass layout="faces"'):
        shtool.project_env(np.ones((6, 8, 8, 3)), 3)
    with pytest.raises(FileNotFoundError, match="f_px.exr"):
        shtool.project_env_file(str(tmp_path / "f_%s.exr"), layout="faces")


def test_messages_say_what_is_wrong_with_out_axis_and_search_lobes():
    with pytest.raises(ValueError, match=r"out must be in this machine's byte order, got >f8"):
        shtool.rotate(np.zeros(16), np.eye(3), out=np.empty(16, ">f8"))
    with pytest.raises(ValueError, match=r"axis=3 is out of range for coeffs of 1 dimension \(shape \(16,\)\)"):
        shtool.rotate(np.zeros(16), np.eye(3), axis=3)
    with pytest.raises(ValueError, match=r"search_lobes: give bands=\[\.\.\.\]"):
        shtool.search_lobes()
