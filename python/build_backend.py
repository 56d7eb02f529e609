"""PEP 517 backend of the `shtool` Python package: the project's own CMake build, then a
wheel zipped with the standard library.

Why in-tree: the usual CMake backends (scikit-build-core, py-build-cmake) are not in
Debian 12 and PyPI may be unreachable, so `pip install --no-build-isolation .` must work
with what Debian ships (cmake, ninja, pybind11-dev). The build tree is the one
scripts/setup.sh makes (build/, or $SHTOOL_BUILD_DIR); a new one is configured for the
interpreter that runs pip (a venv's base interpreter: the extension is the same for
both). An installed wheel and PYTHONPATH=build/python run the same module.
"""
import base64
import hashlib
import os
import pathlib
import re
import shutil
import subprocess
import sys
import sysconfig
import zipfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
NAME = "shtool"


def _version():
    text = (ROOT / "CMakeLists.txt").read_text()
    return re.search(r"project\(shtool VERSION ([0-9.]+)", text).group(1)


def _interpreter():
    # In a venv, the interpreter it was made from (whose headers the module is built with).
    if sys.prefix != sys.base_prefix:
        base = pathlib.Path(sys.base_prefix) / "bin" / f"python{sys.version_info.major}"
        if base.exists():
            return str(base)
    return sys.executable


def _build():
    build = pathlib.Path(os.environ.get("SHTOOL_BUILD_DIR", ROOT / "build"))
    # A tree that exists keeps its settings (its build type, its interpreter): only the
    # module's targets are brought up to date in it.
    if not (build / "CMakeCache.txt").exists():
        configure = ["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                     f"-DPython3_EXECUTABLE={_interpreter()}", "-DSHTOOL_PYTHON=ON"]
        if shutil.which("ninja"):
            configure += ["-G", "Ninja"]
        if shutil.which("ccache"):
            configure += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"]
        subprocess.run(configure, check=True, stdout=sys.stderr)
    subprocess.run(["cmake", "--build", str(build), "-j", str(os.cpu_count() or 2), "--target", "shtool_python",
                    "shtool_python_files"], check=True, stdout=sys.stderr)
    return build / "python" / NAME


def _tag():
    impl = f"cp{sys.version_info.major}{sys.version_info.minor}"
    plat = sysconfig.get_platform().replace("-", "_").replace(".", "_")
    return f"{impl}-{impl}-{plat}"


def _metadata():
    return (f"Metadata-Version: 2.1\nName: {NAME}\nVersion: {_version()}\n"
            "Summary: Spherical harmonics on numpy arrays: the shtool runtime and offline jobs\n"
            "Requires-Python: >=3.9\nRequires-Dist: numpy\n")


def _record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def get_requires_for_build_wheel(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    info = pathlib.Path(metadata_directory) / f"{NAME}-{_version()}.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text(_metadata())
    return info.name


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    package = _build()
    version, tag = _version(), _tag()
    info = f"{NAME}-{version}.dist-info"
    files = {f"{NAME}/{p.name}": p.read_bytes() for p in sorted(package.iterdir())
             if p.is_file() and (p.suffix in (".py", ".so"))}
    # The shipped tables the module reads (rotation helpers, zhf lobes), found beside it.
    files.update({f"{NAME}/tables/{p.name}": p.read_bytes() for p in sorted((package / "tables").glob("*.shtb"))})
    files[f"{info}/METADATA"] = _metadata().encode()
    files[f"{info}/WHEEL"] = (f"Wheel-Version: 1.0\nGenerator: {NAME} build_backend\nRoot-Is-Purelib: false\n"
                              f"Tag: {tag}\n").encode()
    record = [_record_line(n, d) for n, d in files.items()] + [f"{info}/RECORD,,"]
    files[f"{info}/RECORD"] = ("\n".join(record) + "\n").encode()
    wheel = f"{NAME}-{version}-{tag}.whl"
    with zipfile.ZipFile(pathlib.Path(wheel_directory) / wheel, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in files.items():
            z.writestr(name, data)
    return wheel
