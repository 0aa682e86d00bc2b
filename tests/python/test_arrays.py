"""Tests of python/src/arrays.cpp and the batch calls' handling of Python input: dtype conversion
and zero copy, leading dimensions, poses, bad input raising ValueError with crux's message (never a
crash)."""

import os

import numpy as np
import pytest

import crux
from conftest import random_rays, torus, unit_cube


def test_real_c_contiguous_rows_are_read_in_place():
    rays = np.zeros((10, 4, 6), dtype=crux.REAL)
    assert np.shares_memory(crux._crux._read_rows(rays, 6), rays)


def test_other_dtypes_and_layouts_are_converted_once():
    other = np.float64 if crux.REAL == np.float32 else np.float32
    rays = np.arange(60, dtype=other).reshape(10, 6)
    read = crux._crux._read_rows(rays, 6)
    assert read.dtype == crux.REAL and not np.shares_memory(read, rays)
    np.testing.assert_array_equal(read, rays.astype(crux.REAL))
    strided = np.zeros((10, 12), dtype=crux.REAL)[:, ::2]
    assert not np.shares_memory(crux._crux._read_rows(strided, 6), strided)
    ints = crux._crux._read_rows([[1, 2, 3, 4, 5, 6]], 6)
    assert ints.dtype == crux.REAL


def test_answers_do_not_depend_on_the_input_dtype():
    mesh = torus()
    rays = random_rays(mesh, 500).astype(np.float64)
    a = mesh.ray_closest(rays.astype(crux.REAL))
    b = mesh.ray_closest(np.asfortranarray(rays.astype(crux.REAL).astype(np.float64)))
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


def test_empty_batches_give_empty_answers():
    cube = unit_cube()
    hits = cube.ray_closest(np.zeros((0, 6)))
    assert hits.t.shape == (0,) and hits.point.shape == (0, 3)
    assert cube.ray_all(np.zeros((0, 6))).offsets.tolist() == [0]
    assert cube.contains(np.zeros((3, 0, 3))).shape == (3, 0)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda m: m.ray_closest(np.zeros((4, 5))), r"rays: expected shape \(\.\.\., 6\), got \(4, 5\)"),
        (lambda m: m.ray_closest(np.float64(3.0)), r"rays: expected shape"),
        (lambda m: m.ray_closest([["a", "b", "c", "d", "e", "f"]]), r"rays: cannot be read as an array"),
        (lambda m: m.ray_closest(None), r"rays: expected an array"),
        (lambda m: m.ray_any(np.array([[0, 0, 0, 1, 0, 0], [0, 0, np.nan, 1, 0, 0]])), r"rays\[1\]"),
        (lambda m: m.ray_closest(np.zeros((2, 3, 6))), r"rays\[0, 0\]"),  # zero direction
        (lambda m: m.ray_all([[0, 0, 0, 1, 0, np.inf]]), r"rays\[0\]"),
        (lambda m: m.ray_closest(np.r_[np.tile([0, 0, 0, 1, 0, 0], (5, 1)), [[0, 0, 0, 0, 0, 0], [np.nan] * 6]]),
         r"rays\[5\]\.dir is the zero vector"),  # the first bad row, with crux's message
        (lambda m: m.overlaps_spheres([[0, 0, 0, 1], [0, 0, 0, -1], [0, 0, 0, -2]]), r"spheres\[1\]\.radius is negative"),
        (lambda m: m.ray_closest([[0, 0, 0, 1, 0, 0]], max_distance=-1), r"max_distance"),
        (lambda m: m.ray_closest([[0, 0, 0, 1, 0, 0]], threads=-1), r"threads"),
        (lambda m: m.closest_point([[0, 0, np.nan]]), r"points\[0\]"),
        (lambda m: m.contains([[0, 0]]), r"points: expected shape"),
        (lambda m: m.overlaps_spheres([[0, 0, 0, -1]]), r"spheres\[0\]"),
        (lambda m: m.overlaps_aabbs([[1, 0, 0, 0, 1, 1]]), r"aabbs\[0\]"),
        (lambda m: m.overlaps_obbs([np.r_[[0, 0, 0], [1, 1, 1], [1, 0, 0, 1, 0, 0, 0, 0, 1]]]), r"obbs\[0\]"),
        (lambda m: crux.mesh_overlap(m, m, pose_b=np.eye(3)), r"pose_b"),
        (lambda m: crux.mesh_overlap(m, m, pose_b=2 * np.eye(4)), r"pose_b"),
        (lambda m: crux.mesh_overlap(m, m, pose_b=([2, 0, 0, 0], [0, 0, 0])), r"pose_b\.rotation"),
        (lambda m: crux.mesh_distance(m, m, max_distance=np.nan), r"maxDistance|max_distance"),
        (lambda m: crux.contacts(m, "cone", [0, 0, 0, 1]), r"kind"),
        (lambda m: crux.contacts(m, "sphere", [0, 0, 0, 1], margin=-1), r"margin"),
    ],
)
def test_bad_input_raises_value_error_with_the_message(call, message):
    with pytest.raises(ValueError, match=message):
        call(unit_cube())


@pytest.mark.parametrize(
    "vertices, triangles, message",
    [
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]], r"out of range"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, -1]], r"out of range"),
        ([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], [[0, 1, 2]], r"vert"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0.0, 1.0, 2.0]], r"integer"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1]], r"triangles"),
        ([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]], r"vertices: expected shape"),
        (np.zeros((0, 3)), np.zeros((0, 3), dtype=int), r"."),
    ],
)
def test_bad_meshes_raise_value_error(vertices, triangles, message):
    with pytest.raises(ValueError, match=message):
        crux.Mesh(vertices, triangles)


def test_missing_file_raises_value_error_naming_it(tmp_path):
    with pytest.raises(ValueError, match="nothing.off"):
        crux.Mesh.load(str(tmp_path / "nothing.off"))
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n")
    with pytest.raises(ValueError, match="bad.off"):
        crux.Mesh.load(str(bad))


def test_load_in_a_child_process_matches_the_in_process_load(tmp_path):
    exe = os.environ.get("CRUX_EXECUTABLE")
    if not exe:
        pytest.skip("no crux executable in this build")
    obj = tmp_path / "square.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    a = crux.Mesh.load(str(obj))
    b = crux.Mesh.load(str(obj), import_command=[exe, "import-mesh"])
    assert np.array_equal(a.vertices, b.vertices)
    assert np.array_equal(a.triangles, b.triangles)
    with pytest.raises(ValueError, match="cannot start the import command"):
        crux.Mesh.load(str(obj), import_command=[str(tmp_path / "no-such-crux"), "import-mesh"])


def test_poses_in_every_form_give_the_same_transform():
    a, b = unit_cube(), unit_cube()
    angle = np.pi / 3
    q = np.array([np.cos(angle / 2), 0, 0, np.sin(angle / 2)])
    t = np.array([0.9, 0.1, 0.2])
    m = np.eye(4)
    m[:3, :3] = [[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]]
    m[:3, 3] = t
    same_numbers = [(q, t), np.r_[q, t], [q.tolist(), t.tolist()]]
    # the same numbers in any container: the same transform, bit for bit
    answers = {tuple(crux.touching_pairs(a, b, pose_b=p).ravel()) for p in same_numbers}
    assert len(answers) == 1 and len(next(iter(answers))) > 0
    scene = crux.Scene()
    poses = [scene.world_pose(scene.add(a, p)) for p in same_numbers + [m]]
    for p in poses[1:3]:
        np.testing.assert_array_equal(p, poses[0])
    # the matrix gives that rotation up to the rounding of its quaternion
    np.testing.assert_allclose(poses[3], poses[0], atol=1e-6)
    np.testing.assert_allclose(poses[0], m, atol=1e-6)
