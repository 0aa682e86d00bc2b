"""`import crux` works from the build tree and after `cmake --install` into a prefix, both from a
directory outside the source tree, with nothing but PYTHONPATH pointing at the package."""

import os
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR

BUILD_DIR = os.environ.get("CRUX_BUILD_DIR")
CHECK = (
    "import os, numpy as np, crux\n"
    "m = crux.Mesh(np.eye(3), [[0, 1, 2]])\n"
    "assert m.ray_any([[0.2, 0.2, 5, 0, 0, -1]])[0]\n"
    "print(os.path.realpath(crux.__file__))\n"
    "print(os.path.realpath(crux._crux.__file__))\n"
)


def import_from(directory, cwd):
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = directory
    done = subprocess.run([sys.executable, "-c", CHECK], cwd=cwd, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def outside_source(path):
    return not os.path.realpath(path).startswith(os.path.realpath(SOURCE_DIR) + os.sep)


@pytest.mark.skipif(not BUILD_DIR, reason="CRUX_BUILD_DIR is set by CTest (tests/CMakeLists.txt)")
def test_import_from_the_build_tree(tmp_path):
    assert outside_source(tmp_path)
    files = import_from(os.path.join(BUILD_DIR, "python"), tmp_path)
    for f in files:
        assert f.startswith(os.path.realpath(os.path.join(BUILD_DIR, "python", "crux")))


@pytest.mark.skipif(not BUILD_DIR, reason="CRUX_BUILD_DIR is set by CTest (tests/CMakeLists.txt)")
def test_import_after_cmake_install(tmp_path):
    prefix = tmp_path / "prefix"
    done = subprocess.run(["cmake", "--install", BUILD_DIR, "--prefix", str(prefix)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    relative = os.environ["CRUX_PYTHON_INSTALL_DIR"]
    site = prefix / relative
    assert (site / "crux" / "__init__.py").exists() and (site / "crux" / "_crux.pyi").exists()
    work = tmp_path / "elsewhere"
    work.mkdir()
    files = import_from(str(site), work)
    assert len(files) == 2
    for f in files:
        assert f.startswith(os.path.realpath(site)), f
    # the installed package runs the installed command line (when the build has one)
    if not os.environ.get("CRUX_EXECUTABLE"):
        return  # CRUX_BUILD_APPS=OFF: no command line is installed
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "CRUX_EXECUTABLE")}
    env["PYTHONPATH"] = str(site)
    code = (
        "import os, crux\n"
        "from crux.world import _executable\n"
        "print(os.path.realpath(_executable(None)))\n"
        "with crux.World('native') as w:\n"
        "    print(w.request('ray_triangle', triangle=[[0, 0, 0], [1, 0, 0], [0, 1, 0]],\n"
        "                    ray={'origin': [0.2, 0.2, 1], 'dir': [0, 0, -1]})['t'])\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=work, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    exe, t = done.stdout.split()
    assert exe == os.path.realpath(prefix / "bin" / "crux") and float(t) == 1.0
