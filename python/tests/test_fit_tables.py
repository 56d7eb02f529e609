"""fit_zh against the CLI's fit-zh, load_table against the CLI's JSON encoding, the
offline jobs' files against the CLI's bytes."""
import json
import subprocess
import sys

import numpy as np
import pytest

import shtool
from conftest import SOURCE_DIR


def transfer_vectors(count=12, order=4, seed=1):
    """SH vectors that look like transfer: a positive lobe plus noise."""
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(count, 3))
    t = shtool.eval_sh(order, axes) * 2 + 0.1 * rng.normal(size=(count, order * order))
    t[:, 0] += 1.0
    return t


@pytest.mark.parametrize("lobes, effort, seed", [(1, None, None), (3, 2, 7), (4, 1, 3)])
def test_fit_zh_equals_the_cli(cli, tmp_path, lobes, effort, seed):
    t = transfer_vectors()
    (tmp_path / "t.json").write_text(json.dumps({"order": 4, "vectors": t.tolist()}))
    args = ["fit-zh", "--transfer", tmp_path / "t.json", "--out", tmp_path / "fit.shtb", "--lobes", lobes]
    if effort is not None:
        args += ["--effort", effort]
    if seed is not None:
        args += ["--seed", seed]
    cli(*args)
    # The CLI read the vectors from JSON: the same doubles (shortest round trip).
    fit = shtool.fit_zh(t, lobes=lobes, effort=effort, seed=seed)
    table = shtool.load_table(tmp_path / "fit.shtb")
    assert table.kind == "zh-fit" and table.order == 4
    assert fit.axes.shape == (12, lobes, 3) and fit.coeffs.shape == (12, lobes, 4) and fit.residual.shape == (12,)
    np.testing.assert_array_equal(fit.axes.reshape(-1), table.arrays["axes"].reshape(-1))
    np.testing.assert_array_equal(fit.coeffs.reshape(-1), table.arrays["coeffs"].reshape(-1))
    np.testing.assert_array_equal(fit.residual, table.arrays["residual"])
    loaded = shtool.load_zh_fit(tmp_path / "fit.shtb")
    np.testing.assert_array_equal(loaded.axes, fit.axes)


def test_fit_zh_bad_input():
    with pytest.raises(ValueError):
        shtool.fit_zh(np.ones((3, 15)))
    with pytest.raises(ValueError):
        shtool.fit_zh(np.ones((3, 16)), lobes=0)
    with pytest.raises(ValueError):
        shtool.fit_zh(np.ones((3, 16)), effort=9)
    with pytest.raises(TypeError):
        shtool.fit_zh(np.ones((3, 16), np.int64))
    t = np.ones((3, 16))
    t[1, 2] = np.inf
    with pytest.raises(ValueError):
        shtool.fit_zh(t)


def test_load_table_arrays_equal_the_cli_json(cli, tmp_path):
    cli("gen-tensors", "--order", 4, "--out", tmp_path / "bin")
    cli("gen-tensors", "--order", 4, "--out", tmp_path / "json", "--format", "json")
    for path in sorted((tmp_path / "bin").iterdir()):
        table = shtool.load_table(path)
        doc = json.loads(next((tmp_path / "json").glob(path.stem + ".*")).read_text())
        assert table.kind == doc["kind"] and table.order == doc["order"]
        assert table.header["kind"] == doc["kind"]
        for name, values in doc["data"].items():
            a = table.arrays[name]
            assert not a.flags.writeable
            np.testing.assert_array_equal(a.reshape(-1), np.asarray(values, dtype=a.dtype).reshape(-1))


def test_gen_tensors_writes_the_cli_bytes(cli, tmp_path):
    cli("gen-tensors", "--order", 5, "--out", tmp_path / "cli", "--what", "rotation")
    written = shtool.gen_tensors(5, str(tmp_path / "py"), what=["rotation"])
    assert len(written) == 1
    for path in (tmp_path / "cli").iterdir():
        assert (tmp_path / "py" / path.name).read_bytes() == path.read_bytes()


def test_load_table_errors(tmp_path):
    with pytest.raises(ValueError):
        shtool.load_table(tmp_path / "missing.shtb")
    (tmp_path / "bad.shtb").write_bytes(b"\x89SHT\r\n\x1a\nnonsense")
    with pytest.raises(ValueError):
        shtool.load_table(tmp_path / "bad.shtb")


def test_fit_zh_mesh_writes_the_cli_bytes(cli, tmp_path):
    mesh = SOURCE_DIR / "data" / "spot.obj"
    opts = ["--order", 3, "--lobes", 2, "--rays", 64, "--effort", 1]
    cli("fit-zh", mesh, "--out", tmp_path / "cli.shtb", *opts)
    fit = shtool.fit_zh_mesh(mesh, out=str(tmp_path / "py.shtb"), order=3, lobes=2, rays=64, effort=1)
    assert (tmp_path / "py.shtb").read_bytes() == (tmp_path / "cli.shtb").read_bytes()
    assert fit.axes.shape[1:] == (2, 3)


def test_transform_splats_writes_the_cli_bytes(cli, tmp_path):
    # A tiny 3DGS PLY of degree 1: position, dc, rest (3 x 3), opacity, scale, rotation.
    names = (["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2"] + [f"f_rest_{i}" for i in range(9)] +
             ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"])
    rng = np.random.default_rng(4)
    data = rng.normal(size=(5, len(names))).astype("<f4")
    header = "ply\nformat binary_little_endian 1.0\nelement vertex 5\n"
    header += "".join(f"property float {n}\n" for n in names) + "end_header\n"
    (tmp_path / "in.ply").write_bytes(header.encode() + data.tobytes())
    cli("transform-splats", tmp_path / "in.ply", "--out", tmp_path / "cli.ply", "--quat", "0.8,0.6,0,0",
        "--scale", 2)
    report = shtool.transform_splats(str(tmp_path / "in.ply"), str(tmp_path / "py.ply"),
                                     quaternion=(0.8, 0.6, 0, 0), scale=2.0)
    assert report["splats"] == 5
    assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
    # The same transform on arrays in memory.
    written = np.frombuffer((tmp_path / "cli.ply").read_bytes()[len(header):], "<f4").reshape(5, len(names))
    sh = np.stack([np.concatenate([data[:, 3 + c:4 + c], data[:, 6 + 3 * c:9 + 3 * c]], axis=1) for c in range(3)],
                  axis=1)  # (S, 3, 4): dc, then rest of channel c
    for given in (dict(quaternion=(0.8, 0.6, 0, 0)), dict(matrix=shtool.quat_to_matrix([0.8, 0.6, 0.0, 0.0]))):
        moved = shtool.transform_splat_arrays(sh=sh, positions=data[:, :3], rotations=data[:, 19:23],
                                              log_scales=data[:, 16:19], scale=2.0, **given)
        np.testing.assert_allclose(moved["positions"], written[:, :3], rtol=1e-6)
        np.testing.assert_allclose(moved["rotations"], written[:, 19:23], rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(moved["log_scales"], written[:, 16:19], rtol=1e-6)
        for c in range(3):
            np.testing.assert_allclose(moved["sh"][:, c, 1:], written[:, 6 + 3 * c:9 + 3 * c], atol=1e-6)


def test_search_lobes_returns_the_summary(tmp_path):
    summary = shtool.search_lobes(bands=[2], seed=1, threads=1, population=40, stall=5, restarts=1,
                                  json=str(tmp_path / "s.json"))
    assert json.loads((tmp_path / "s.json").read_text()) == summary
    with pytest.raises(TypeError):
        shtool.search_lobes(bands=[2], colour="red")


@pytest.mark.parametrize("cls, name", [
    (shtool.RotationHelpers, "rotation-helpers.shtb"), (shtool.TriplingTensor, "tripling-tensor.shtb"),
    (shtool.ShFourierTensors, "sh-fourier-tensors.shtb"), (shtool.ZhfLobes, "zhf-shared-N4.shtb"),
])
def test_typed_loaders_of_the_shipped_tables(cls, name):
    t = cls.load(SOURCE_DIR / "tables" / name)
    assert t.kind == cls.KIND and t.arrays
    first = next(iter(t.arrays))
    assert getattr(t, first) is t.arrays[first]


def test_typed_loaders_refuse_other_kinds(tmp_path, cli):
    with pytest.raises(ValueError):
        shtool.ZhFitTable.load(SOURCE_DIR / "tables" / "rotation-helpers.shtb")
    cli("light", "--type", "constant", "--order", 2, "--json", tmp_path / "l.json", "--out", tmp_path / "l.shtb")
    env = shtool.EnvSh.load(tmp_path / "l.shtb")
    assert env.coefficients.shape == (4, 3)


def test_gen_tensors_that_fails_leaves_no_folder(tmp_path):
    # Out of memory while computing (the address space limited in a child process): the
    # job fails, and the folder it would have made is not there.
    code = ("import resource, sys, numpy, shtool\n"
            "vm = [int(l.split()[1]) for l in open('/proc/self/status') if l.startswith('VmSize:')][0] * 1024\n"
            "resource.setrlimit(resource.RLIMIT_AS, (vm + 2**22, vm + 2**22))\n"
            "try:\n"
            "    shtool.gen_tensors(16, sys.argv[1], what=['tripling'])\n"
            "except MemoryError:\n"
            "    print('failed')\n")
    r = subprocess.run([sys.executable, "-c", code, str(tmp_path / "new" / "tables")], capture_output=True, text=True)
    assert r.stdout == "failed\n", r.stderr
    assert not (tmp_path / "new").exists()
