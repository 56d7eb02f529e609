"""fit_zh against the CLI's fit-zh, load_table against the CLI's JSON encoding, the
offline jobs' files against the CLI's bytes."""
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import shtool
from conftest import SOURCE_DIR
from gil import RELEASED_SHARE, gil_free_share


def transfer_vectors(count=12, order=4, seed=1):
    """SH vectors that look like transfer: a positive lobe plus noise."""
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(count, 3))
    t = shtool.eval_sh(order, axes) * 2 + 0.1 * rng.normal(size=(count, order * order))
    t[:, 0] += 1.0
    return t


def write_splats(path, seed=4, count=5):
    """A small 3DGS PLY of degree 1: position, dc, rest (3 x 3), opacity, scale, rotation.
    Returns (property names, values (count, properties) float32, header text)."""
    names = (["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2"] + [f"f_rest_{i}" for i in range(9)] +
             ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"])
    data = np.random.default_rng(seed).normal(size=(count, len(names))).astype("<f4")
    header = f"ply\nformat binary_little_endian 1.0\nelement vertex {count}\n"
    header += "".join(f"property float {n}\n" for n in names) + "end_header\n"
    path.write_bytes(header.encode() + data.tobytes())
    return names, data, header


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
    # Finite, but the norm (or in float32 the fit) beyond the dtype: refused, not returned
    # as inf and NaN.
    with pytest.raises(ValueError, match="beyond double's range"):
        shtool.fit_zh(np.full((1, 16), 1.7e308))
    base = np.random.default_rng(3).normal(size=(1, 16))
    with pytest.raises(ValueError, match="overflows float32"):
        shtool.fit_zh((base / np.abs(base).max() * 3e38).astype(np.float32), lobes=3)


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
    # A missing file is an OSError, as open() raises, for every call that reads one.
    for call in (shtool.load_table, shtool.load_zh_fit, shtool.fit_zh_mesh, shtool.project_env_file,
                 lambda p: shtool.transform_splats(p, tmp_path / "out.ply")):
        with pytest.raises(FileNotFoundError, match="no such file"):
            call(tmp_path / "missing.shtb")
    assert not (tmp_path / "out.ply").exists()
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
    # Seeds take the CLI's whole range (unsigned 64 bits).
    cli("fit-zh", mesh, "--out", tmp_path / "cli-seed.shtb", "--seed", 2**64 - 5, *opts)
    shtool.fit_zh_mesh(mesh, out=tmp_path / "py-seed.shtb", seed=2**64 - 5, order=3, lobes=2, rays=64, effort=1)
    assert (tmp_path / "py-seed.shtb").read_bytes() == (tmp_path / "cli-seed.shtb").read_bytes()
    for seed in (-1, 2**64):
        with pytest.raises(ValueError, match="seed"):
            shtool.fit_zh_mesh(mesh, seed=seed)


def test_transform_splats_writes_the_cli_bytes(cli, tmp_path):
    names, data, header = write_splats(tmp_path / "in.ply")
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


def test_fit_zh_keeps_float32():
    t = transfer_vectors()
    fit64 = shtool.fit_zh(t, lobes=2, effort=1)
    fit32 = shtool.fit_zh(t.astype(np.float32), lobes=2, effort=1, direct=True)
    for name in ("axes", "coeffs", "residual", "norm", "direct"):
        assert getattr(fit32, name).dtype == np.float32
        assert getattr(fit64, name).dtype == np.float64
    # Fitted in float64 (as the CLI) from the float32 values, then rounded.
    again = shtool.fit_zh(t.astype(np.float32).astype(np.float64), lobes=2, effort=1, direct=True)
    np.testing.assert_array_equal(fit32.axes, again.axes.astype(np.float32))


def test_job_keywords_of_the_wrong_type_are_type_errors(tmp_path):
    mesh = SOURCE_DIR / "data" / "spot.obj"
    sky = SOURCE_DIR / "data" / "sky.hdr"
    write_splats(tmp_path / "in.ply")
    for call, name in [
        (lambda: shtool.fit_zh_mesh(mesh, order="2"), "order"),
        (lambda: shtool.fit_zh_mesh(mesh, lobes=2.0), "lobes"),
        (lambda: shtool.fit_zh_mesh(mesh, direct="yes"), "direct"),
        (lambda: shtool.fit_zh_mesh(mesh, out=3), "out"),
        (lambda: shtool.gen_tensors(3, tmp_path / "g", what=3), "what"),
        (lambda: shtool.search_lobes(bands=2.5), "bands"),
        (lambda: shtool.project_env_file(sky, window="hann", cutoff="2"), "cutoff"),
        (lambda: shtool.project_env_file(sky, window=3), "window"),
        (lambda: shtool.transform_splats(tmp_path / "in.ply", tmp_path / "o.ply", scale="2"), "scale"),
        (lambda: shtool.transform_splats(tmp_path / "in.ply", tmp_path / "o.ply", matrix="eye"), "matrix"),
        (lambda: shtool.transform_splats(tmp_path / "in.ply", tmp_path / "o.ply", translate=(1, 2)), "translate"),
        (lambda: shtool.transform_splats(3, tmp_path / "o.ply"), "path_in"),
    ]:
        with pytest.raises(TypeError, match=name):
            call()
    assert not (tmp_path / "g").exists() and not (tmp_path / "o.ply").exists()


def test_transform_splats_takes_a_3x3_matrix(cli, tmp_path):
    write_splats(tmp_path / "in.ply")
    r = shtool.quat_to_matrix([0.8, 0.0, 0.6, 0.0])
    cli("transform-splats", tmp_path / "in.ply", "--out", tmp_path / "cli.ply", "--matrix",
        ",".join(repr(float(x)) for x in r.ravel()))
    for given in (r, r.ravel(), tuple(r.ravel()), r.tolist()):
        shtool.transform_splats(tmp_path / "in.ply", tmp_path / "py.ply", matrix=given)
        assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
    with pytest.raises(TypeError, match="matrix"):
        shtool.transform_splats(tmp_path / "in.ply", tmp_path / "py.ply", matrix=np.eye(4))


def test_job_keywords_are_the_cli_options(cli, tmp_path):
    # fit-zh --up, --shard.
    quad = tmp_path / "quad.obj"
    quad.write_text("v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 4 3 2\n")
    opts = ["--order", 3, "--lobes", 1, "--rays", 64, "--effort", 1]
    cli("fit-zh", quad, "--out", tmp_path / "cli.shtb", "--up", "z", *opts)
    shtool.fit_zh_mesh(quad, out=tmp_path / "py.shtb", up="z", order=3, lobes=1, rays=64, effort=1)
    assert (tmp_path / "py.shtb").read_bytes() == (tmp_path / "cli.shtb").read_bytes()
    assert shtool.load_table(tmp_path / "py.shtb").header["meta"]["mesh_up"] == "z"
    cli("fit-zh", quad, "--out", tmp_path / "cli-part.shtb", "--shard", "1/2", *opts)
    part = shtool.fit_zh_mesh(quad, out=tmp_path / "py-part.shtb", shard="1/2", order=3, lobes=1, rays=64, effort=1)
    assert (tmp_path / "py-part.shtb").read_bytes() == (tmp_path / "cli-part.shtb").read_bytes()
    assert isinstance(part, shtool.Table) and list(part.vertex_index) == [2, 3]
    # project-env --render-back, --render-source.
    sky = SOURCE_DIR / "data" / "sky.hdr"
    cli("project-env", sky, "--order", 3, "--json", tmp_path / "l.json", "--render-back", tmp_path / "cli-back.png",
        "--render-source", tmp_path / "cli-source.png")
    shtool.project_env_file(sky, order=3, render_back=tmp_path / "py-back.png",
                            render_source=tmp_path / "py-source.png")
    for name in ("back", "source"):
        assert (tmp_path / f"py-{name}.png").read_bytes() == (tmp_path / f"cli-{name}.png").read_bytes()
    # transform-splats --quat, --sh-degree, --frame, --spz-frame, --sh-bits, --spz-version.
    write_splats(tmp_path / "in.ply")
    cli("transform-splats", tmp_path / "in.ply", "--out", tmp_path / "cli.spz", "--quat", "0.8,0,0.6,0",
        "--sh-degree", 1, "--frame", "RUB", "--spz-frame", "LUF", "--sh-bits", "6,5", "--spz-version", 3)
    shtool.transform_splats(tmp_path / "in.ply", tmp_path / "py.spz", quat=(0.8, 0, 0.6, 0), sh_degree=1,
                            frame="RUB", spz_frame="LUF", sh_bits=(6, 5), spz_version=3)
    assert (tmp_path / "py.spz").read_bytes() == (tmp_path / "cli.spz").read_bytes()
    # gen-tensors --what as the CLI's comma-separated list.
    paths = shtool.gen_tensors(3, tmp_path / "t", what="rotation,tripling")
    assert [pathlib.Path(p).name for p in paths] == ["rotation-helpers.shtb", "tripling-tensor.shtb"]
    # search-lobes --band, --bands a-b, and the search options.
    options = dict(seed=1, threads=1, population=40, stall=5, restarts=1, crossover=0.7, mutation=0.1, elitism=1,
                   max_generations=50, theta_candidates="pooled", max_cond=100.0, no_local_search=True,
                   no_secondary=True)
    cli("search-lobes", "--bands", "2-3", "--json", tmp_path / "cli.json", "--seed", 1, "--threads", 1,
        "--population", 40, "--stall", 5, "--restarts", 1, "--crossover", 0.7, "--mutation", 0.1, "--elitism", 1,
        "--max-generations", 50, "--theta-candidates", "pooled", "--max-cond", 100, "--no-local-search",
        "--no-secondary", "--quiet")
    summary = json.loads((tmp_path / "cli.json").read_text())
    assert shtool.search_lobes(bands="2-3", **options) == summary
    assert shtool.search_lobes(bands=[2, 3], **options) == summary
    assert shtool.search_lobes(band=2, **options)["bands"] == summary["bands"][:1]


def test_paths_may_be_str_bytes_or_pathlike(cli, tmp_path):
    write_splats(tmp_path / "in.ply")
    shtool.transform_splats(tmp_path / "in.ply", tmp_path / "a.ply", scale=2.0)
    shtool.transform_splats(os.fsencode(tmp_path / "in.ply"), str(tmp_path / "b.ply"), scale=2.0)
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()
    written = shtool.gen_tensors(2, tmp_path / "t", what=["rotation"])
    assert written == [str(tmp_path / "t" / "rotation-helpers.shtb")]
    for given in (pathlib.Path(written[0]), written[0], os.fsencode(written[0])):
        assert shtool.load_table(given).kind == "rotation-helpers"
        assert shtool.RotationHelpers.load(given).order == 2
    with pytest.raises(TypeError, match="path"):
        shtool.load_table(3)
    fit = shtool.fit_zh_mesh(SOURCE_DIR / "data" / "spot.obj", out=tmp_path / "f.shtb", json=tmp_path / "f.json",
                             order=2, lobes=1, rays=16, effort=1)
    assert (tmp_path / "f.json").exists()
    np.testing.assert_array_equal(shtool.load_zh_fit(os.fsencode(tmp_path / "f.shtb")).axes, fit.axes)


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


def test_transform_splat_arrays_as_the_job(cli, tmp_path):
    # The job's own arithmetic: the values the CLI writes, to the bit (3000 splats: a
    # second implementation differed in the last bit of 1-2 % of them).
    names, data, header = write_splats(tmp_path / "in.ply", count=3000)
    sh = np.stack([np.concatenate([data[:, 3 + c:4 + c], data[:, 6 + 3 * c:9 + 3 * c]], axis=1) for c in range(3)],
                  axis=1)  # (S, 3, 4)
    arrays = dict(sh=sh, positions=data[:, :3], rotations=data[:, 19:23], log_scales=data[:, 16:19])
    # A reflection (det -1) and a quaternion of length 2, both taken by the job.
    q = 2 * np.array([0.8, 0.2, -0.4, 0.4]) / np.linalg.norm([0.8, 0.2, -0.4, 0.4])
    mirror = np.diag([1.0, 1.0, -1.0]) @ shtool.quat_to_matrix(q / 2)
    for flag, value, given in [("--matrix", mirror.ravel(), dict(matrix=mirror)), ("--quat", q, dict(quaternion=q))]:
        cli("transform-splats", tmp_path / "in.ply", "--out", tmp_path / "cli.ply", flag,
            ",".join(repr(float(x)) for x in value), "--scale", 2.5, "--translate", "1,-2,3")
        written = np.frombuffer((tmp_path / "cli.ply").read_bytes()[len(header):], "<f4").reshape(len(data), -1)
        moved = shtool.transform_splat_arrays(**arrays, scale=2.5, translate=(1, -2, 3), **given)
        np.testing.assert_array_equal(moved["positions"], written[:, :3])
        np.testing.assert_array_equal(moved["rotations"], written[:, 19:23])
        np.testing.assert_array_equal(moved["log_scales"], written[:, 16:19])
        for c in range(3):
            np.testing.assert_array_equal(moved["sh"][:, c, 1:], written[:, 6 + 3 * c:9 + 3 * c])
    with pytest.raises(ValueError, match="quaternion"):
        shtool.transform_splat_arrays(positions=data[:, :3], quaternion=(0, 0, 0, 0))
    with pytest.raises(ValueError, match="orthogonal"):
        shtool.transform_splat_arrays(positions=data[:, :3], matrix=2 * np.eye(3))


def test_transform_splat_arrays_float32_sh_are_the_jobs_bits(cli, tmp_path):
    # float32 SH are rotated in float64 and rounded once, as the job does.
    names, data, header = write_splats(tmp_path / "in.ply")
    cli("transform-splats", tmp_path / "in.ply", "--out", tmp_path / "cli.ply", "--quat", "0.3,0.5,-0.7,0.2")
    written = np.frombuffer((tmp_path / "cli.ply").read_bytes()[len(header):], "<f4").reshape(5, len(names))
    sh = np.stack([np.concatenate([data[:, 3 + c:4 + c], data[:, 6 + 3 * c:9 + 3 * c]], axis=1) for c in range(3)],
                  axis=1)
    assert sh.dtype == np.float32
    moved = shtool.transform_splat_arrays(sh=sh, quaternion=(0.3, 0.5, -0.7, 0.2))["sh"]
    assert moved.dtype == np.float32
    for c in range(3):
        np.testing.assert_array_equal(moved[:, c, 1:], written[:, 6 + 3 * c:9 + 3 * c])


@pytest.mark.parametrize("arrays, message", [
    (dict(positions=np.ones((2, 2))), r"positions must have shape \(S, 3\), got \(2, 2\)"),
    (dict(normals=np.ones(3)), r"normals must have shape \(S, 3\), got \(3,\)"),
    (dict(rotations=np.ones((2, 3))), r"rotations must have shape \(S, 4\), got \(2, 3\)"),
    (dict(log_scales=np.ones((2, 2))), r"log_scales must have shape \(S, 3\), got \(2, 2\)"),
    (dict(sh=np.ones((2, 3, 5))), r"sh must have shape \(S, 3, N\*\*2\), got \(2, 3, 5\)"),
    (dict(sh=np.ones((2, 16))), r"sh must have shape \(S, 3, N\*\*2\), got \(2, 16\)"),
])
def test_transform_splat_arrays_checks_shapes(arrays, message):
    with pytest.raises(ValueError, match=message):
        shtool.transform_splat_arrays(**arrays, quaternion=(0.8, 0.6, 0, 0))


def test_transform_splat_arrays_converts_integers_to_float():
    moved = shtool.transform_splat_arrays(positions=np.array([[1, 1, 1]]), normals=np.array([[0, 0, 1]]),
                                          log_scales=np.zeros((1, 3), np.int32), rotations=np.array([[1, 0, 0, 0]]),
                                          sh=np.ones((1, 3, 4), np.int64), quaternion=(1, 0, 0, 0), scale=1.5)
    np.testing.assert_array_equal(moved["positions"], [[1.5, 1.5, 1.5]])
    np.testing.assert_allclose(moved["log_scales"], np.log(1.5))
    for name, a in moved.items():
        assert a.dtype == np.float64, name
    assert shtool.transform_splat_arrays(positions=np.ones((1, 3), np.float32))["positions"].dtype == np.float32


def test_table_loaders_release_the_gil(cli, tmp_path):
    t = np.random.default_rng(8).normal(size=(300_000, 4))
    t[:, 0] += 3
    (tmp_path / "t.json").write_text(json.dumps({"order": 2, "vectors": t.tolist()}))
    cli("fit-zh", "--transfer", tmp_path / "t.json", "--out", tmp_path / "big.shtb", "--lobes", 1, "--effort", 1)
    for load in (shtool.load_zh_fit, shtool.ZhFitTable.load, shtool.load_table):
        share, _ = gil_free_share(lambda: load(tmp_path / "big.shtb"))
        assert share > RELEASED_SHARE, load
