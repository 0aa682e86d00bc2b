"""Fixtures of the Python module's tests (tests/python): meshes built in numpy, the real meshes of
data/meshes when extracted (scripts/setup), and seeded random rays and points.

CTest runs these files with Debian's interpreter and PYTHONPATH=<build>/python (tests/CMakeLists.txt);
CRUX_SOURCE_DIR, CRUX_BUILD_DIR and CRUX_EXECUTABLE tell them where the rest of the build is."""

import os

import numpy as np
import pytest

import crux

SOURCE_DIR = os.environ.get("CRUX_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


def unit_cube(scale=1.0):
    """The closed cube [0, scale]^3, 12 triangles, outward counter-clockwise."""
    v = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=np.float64) * scale
    t = np.array(
        [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
         [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]]
    )
    return crux.Mesh(v, t, "cube")


def torus(rings=24, segments=16, big=2.0, small=0.6):
    """A closed, consistently oriented torus (every edge shared by two triangles)."""
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    u = 2 * np.pi * i / rings
    w = 2 * np.pi * j / segments
    r = big + small * np.cos(w)
    v = np.stack([r * np.cos(u), r * np.sin(u), small * np.sin(w)], axis=-1).reshape(-1, 3)
    at = lambda a, b: (a % rings) * segments + (b % segments)  # noqa: E731
    tris = []
    for a in range(rings):
        for b in range(segments):
            tris.append([at(a, b), at(a + 1, b), at(a + 1, b + 1)])
            tris.append([at(a, b), at(a + 1, b + 1), at(a, b + 1)])
    return crux.Mesh(v, np.array(tris), "torus")


def grid_plane(n=8):
    """The integer grid [0, n]^2 at z = 0, each unit square split along its diagonal (open sheet)."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    v = np.stack([i, j, np.zeros_like(i)], axis=-1).reshape(-1, 3).astype(np.float64)
    at = lambda a, b: a * (n + 1) + b  # noqa: E731
    tris = []
    for a in range(n):
        for b in range(n):
            tris.append([at(a, b), at(a + 1, b), at(a + 1, b + 1)])
            tris.append([at(a, b), at(a + 1, b + 1), at(a, b + 1)])
    return crux.Mesh(v, np.array(tris), "grid")


def random_rays(mesh, n, seed=1):
    """Rays from a sphere around the mesh's bounds towards random points inside them (some miss)."""
    rng = np.random.default_rng(seed)
    lo, hi = mesh.bounds.astype(np.float64)
    center, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    d = rng.normal(size=(n, 3))
    origins = center + radius * d / np.linalg.norm(d, axis=1, keepdims=True)
    targets = lo + (hi - lo) * rng.uniform(-0.2, 1.2, size=(n, 3))
    return crux.rays(origins, targets - origins)


def random_points(mesh, n, seed=2, margin=0.3):
    rng = np.random.default_rng(seed)
    lo, hi = mesh.bounds.astype(np.float64)
    ext = hi - lo
    return (lo - margin * ext + (1 + 2 * margin) * ext * rng.uniform(size=(n, 3))).astype(crux.REAL)


def mesh_path(name):
    return os.path.join(SOURCE_DIR, "data", "meshes", name)


@pytest.fixture(scope="session")
def bunny():
    path = mesh_path("bunny00.off")
    if not os.path.exists(path):
        pytest.skip("data/meshes/bunny00.off is not extracted (scripts/setup)")
    return crux.Mesh.load(path)


def run_in_child(code, payload):
    """Runs `code` in a new interpreter (the same one, same environment) with `payload` (bytes) on
    its standard input; returns its standard output (bytes). The child sees crux as we do."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", code], input=payload, capture_output=True, timeout=120)
    assert done.returncode == 0, done.stderr.decode(errors="replace")
    return done.stdout


def evaluate_in_child(obj, rays, expressions):
    """Pickles (obj, rays) to a new interpreter, which evaluates each expression (`obj` and `rays` in
    scope) and sends the results back as arrays: {name: array}."""
    import io
    import pickle

    code = (
        "import sys, pickle, io, numpy as np\n"
        "obj, rays = pickle.loads(sys.stdin.buffer.read())\n"
        "buf = io.BytesIO()\n"
        "np.savez(buf, **{k: eval(e) for k, e in %r.items()})\n"
        "sys.stdout.buffer.write(buf.getvalue())\n" % (expressions,)
    )
    out = np.load(io.BytesIO(run_in_child(code, pickle.dumps((obj, rays)))))
    return {k: out[k] for k in expressions}
