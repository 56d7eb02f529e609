"""Paths the tests share: the source tree and the built `shtool` command (ctest passes
SHTOOL_EXE; run by hand, build/shtool)."""
import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("SHTOOL_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SHTOOL_EXE = os.environ.get("SHTOOL_EXE", str(SOURCE_DIR / "build" / "shtool"))


@pytest.fixture
def cli():
    """Runs `shtool ARGS...` and returns its stdout; a failure fails the test."""
    def run(*args, cwd=None):
        r = subprocess.run([SHTOOL_EXE, *map(str, args)], capture_output=True, text=True, cwd=cwd)
        assert r.returncode == 0, r.stderr
        return r.stdout
    return run
