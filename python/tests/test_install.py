"""`pip install --no-build-isolation .` into a venv of Debian's interpreter, with no
package index: the in-tree backend builds the module with the project's CMake build."""
import os
import subprocess

from conftest import SOURCE_DIR


def test_pip_install_into_a_venv(tmp_path):
    venv = tmp_path / "venv"
    subprocess.run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", str(venv)], check=True)
    env = dict(os.environ, PIP_NO_INDEX="1", PIP_NO_CACHE_DIR="1")
    env.pop("PYTHONPATH", None)
    env.pop("SHTOOL_TABLES", None)  # the installed package finds its own tables
    env.setdefault("SHTOOL_BUILD_DIR", str(SOURCE_DIR / "build"))
    r = subprocess.run([str(venv / "bin" / "pip"), "install", "--no-build-isolation", str(SOURCE_DIR)],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run([str(venv / "bin" / "python"), "-c",
                        "import shtool, numpy; print(shtool.__file__); print(shtool.eval_sh(2, numpy.ones(3)).shape); "
                        "print(shtool.rotate(numpy.ones(100), numpy.eye(3), method='zhf').shape)"],
                       capture_output=True, text=True, env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert str(venv) in r.stdout and "(4,)" in r.stdout and "(100,)" in r.stdout
