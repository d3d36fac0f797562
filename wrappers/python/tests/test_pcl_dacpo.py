# SPDX-License-Identifier: BSD-3-Clause
"""pcl_dacpo from Python: known answers on generated scenes, parameter and
input checks, dtype/order variants, cancel, agreement with the C tool, and no
leaks over many calls. Run by ctest (label python) with PYTHONPATH set to the
build tree."""
import gc
import os
import resource
import struct
import subprocess
import sys

import numpy as np
import pytest

import pcl_dacpo


def right_as_given(normals, gt):
    return 100.0 * np.mean(np.einsum("ij,ij->i", normals, gt) > 0)


def wrong_up_to_flip(normals, gt):
    r = right_as_given(normals, gt)
    return min(100.0 - r, r)


# ---- known answers -----------------------------------------------------------

def test_open_box_estimated_normals_face_into_the_box():
    pts, gt = pcl_dacpo.make_scene("box", 10000, seed=1)
    normals, result = pcl_dacpo.orient(pts)
    assert normals.shape == (10000, 3) and normals.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-4)
    # measured: 100 % (seed 1); one wrong wall would cost > 15 %
    assert right_as_given(normals, gt) > 99.0
    assert result.stats["input_points"] == 10000
    assert result.stats["num_components"] == 1
    assert result.block_labels.shape == (10000,)
    assert result.block_flips.shape == (result.stats["num_blocks"],)
    assert result.confidence.min() >= 0.0 and result.confidence.max() <= 1.0
    # the work of stages 2-3: each block ran 4 (the first agreed) or all 16 restarts
    nb = result.stats["num_blocks"]
    all16 = result.stats["dipole_blocks_all_restarts"]
    assert result.stats["dipole_restarts_total"] == 4 * nb + 12 * all16
    assert result.stats["ipsr_iterations_total"] >= result.stats["ipsr_iterations_max"] > 0
    assert result.stats["ipsr_faces_total"] > 0


def test_sphere_given_axes_come_out_outward():
    pts, gt = pcl_dacpo.make_scene("sphere", 3000, seed=2)
    rng = np.random.default_rng(0)
    axes = gt * rng.choice([-1.0, 1.0], size=(len(gt), 1)).astype(np.float32)
    normals, result = pcl_dacpo.orient(pts, axes, ipsr_enabled=False)
    assert right_as_given(normals, gt) > 99.0
    assert result.stats["sign_enclosed"]
    # the given axes are kept, only their signs change
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", normals, axes)), 1.0, atol=1e-5)


def test_viewpoint_and_keep_policies():
    pts, gt = pcl_dacpo.make_scene("box", 6000, seed=2)
    # a viewpoint far out below the box's x = 0, y = 0 corner: the one sign under
    # which most normals face it turns the box inside out
    normals, result = pcl_dacpo.orient(pts, viewpoint=(-1000.0, -1000.0, -1000.0),
                                       ipsr_enabled=False)
    assert right_as_given(normals, gt) < 1.0
    kept, _ = pcl_dacpo.orient(pts, sign_policy="keep", ipsr_enabled=False)
    assert wrong_up_to_flip(kept, gt) < 1.0


# ---- parameters and inputs ------------------------------------------------------

def test_scan_kind_is_decided_reported_and_can_be_given():
    pts, gt = pcl_dacpo.make_scene("room", 8000, seed=5)
    normals, res = pcl_dacpo.orient(pts, ipsr_enabled=False)
    assert res.stats["scan_kind"] == "multi_view"
    assert res.stats["single_view_fit"] < 0.5
    assert res.stats["dipole_c_used"] == 1.5 and res.stats["dipole_layers_used"] == 2.0
    _, single = pcl_dacpo.orient(pts, scan_kind="single_view", ipsr_enabled=False)
    assert single.stats["scan_kind"] == "single_view"
    assert single.stats["single_view_fit"] == 0.0
    assert single.stats["dipole_c_used"] == 1.0 and single.stats["dipole_layers_used"] == 0.5
    assert single.stats["dipole_two_sheet_used"] == 0.0
    assert pcl_dacpo.default_params()["scan_kind"] == "auto"
    with pytest.raises(ValueError, match="scan_kind must be one of"):
        pcl_dacpo.orient(pts, scan_kind="depth")


def test_unknown_parameter_names_the_nearest():
    pts, _ = pcl_dacpo.make_scene("plane", 500)
    with pytest.raises(TypeError, match="'kk'.*did you mean 'k'"):
        pcl_dacpo.orient(pts, kk=5)
    with pytest.raises(TypeError, match="seed must be an int"):
        pcl_dacpo.orient(pts, seed="one")
    # ints too large for the C field are a ValueError naming the keyword
    with pytest.raises(ValueError, match="k=.*not a value"):
        pcl_dacpo.orient(pts, k=2**70)
    with pytest.raises(ValueError, match="seed=.*not a value"):
        pcl_dacpo.orient(pts, seed=2**64)
    with pytest.raises(ValueError, match="dipole_c"):
        pcl_dacpo.orient(pts, dipole_c=0.5)
    with pytest.raises(ValueError, match="edge_weight must be one of"):
        pcl_dacpo.orient(pts, edge_weight="magic")
    with pytest.raises(ValueError, match="viewpoint must be three finite"):
        pcl_dacpo.orient(pts, viewpoint=(0, 0, float("nan")))
    assert pcl_dacpo.default_params()["edge_weight"] == "vcr"
    assert pcl_dacpo.default_params()["k"] == 10
    assert pcl_dacpo.default_params()["cue_anchor"] == 1.0
    with pytest.raises(ValueError, match="cue_anchor"):
        pcl_dacpo.orient(pts, cue_anchor=-1.0)
    assert pcl_dacpo.default_params()["seam_dipole"] == 0.5
    assert pcl_dacpo.default_params()["vcr_image_size"] == 128
    assert pcl_dacpo.default_params()["surface_vote"] == 500
    with pytest.raises(ValueError, match="seam_dipole"):
        pcl_dacpo.orient(pts, seam_dipole=-1.0)
    assert pcl_dacpo.default_params()["adaptive_normals"] in (False, True)
    plane, gt = pcl_dacpo.make_scene("plane", 500)
    normals, _ = pcl_dacpo.orient(plane, adaptive_normals=True)
    assert wrong_up_to_flip(normals, gt) < 1.0


def test_bad_inputs_raise_clear_errors():
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        pcl_dacpo.orient(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="shape of points"):
        pcl_dacpo.orient(np.zeros((10, 3)), np.zeros((9, 3)))
    with pytest.raises(TypeError, match="must hold numbers"):
        pcl_dacpo.orient(np.array([["a", "b", "c"]]))
    with pytest.raises(pcl_dacpo.DacpoError) as e:
        pcl_dacpo.orient(np.zeros((0, 3)))
    assert e.value.status == 2 and "empty" in e.value.status_name
    # NaN rows as in the PCL class and the CLI: NaN normals and labels -1 there,
    # the rest oriented as without them
    pts, gt = pcl_dacpo.make_scene("box", 3000, seed=3)
    ref, _ = pcl_dacpo.orient(np.delete(pts, [7, 100], axis=0), ipsr_enabled=False, seed=2)
    pts[7, 1] = np.nan
    pts[100, 0] = np.inf
    got, res = pcl_dacpo.orient(pts, ipsr_enabled=False, seed=2)
    assert got.shape == (3000, 3)
    assert np.isnan(got[[7, 100]]).all() and np.isfinite(np.delete(got, [7, 100], axis=0)).all()
    np.testing.assert_array_equal(np.delete(got, [7, 100], axis=0), ref)
    assert res.block_labels[7] == -1 and res.component_labels[100] == -1
    assert np.isnan(res.confidence[7]) and len(res.confidence) == 3000


def test_an_open3d_cloud_names_orient_o3d():
    class FakeO3dCloud:  # what orient() sees of an open3d.geometry.PointCloud
        points = np.zeros((10, 3))

        def has_normals(self):
            return False
    with pytest.raises(TypeError, match="orient_o3d"):
        pcl_dacpo.orient(FakeO3dCloud())


def test_dtype_and_memory_order_do_not_change_the_answer():
    pts, _ = pcl_dacpo.make_scene("box", 3000, seed=3)
    ref, _ = pcl_dacpo.orient(pts, ipsr_enabled=False, seed=2)
    for variant in (pts.astype(np.float64), np.asfortranarray(pts), pts.tolist(),
                    np.asfortranarray(pts.astype(np.float64))):
        got, _ = pcl_dacpo.orient(variant, ipsr_enabled=False, seed=2)
        np.testing.assert_array_equal(got, ref)


def test_georeferenced_float64_keeps_its_precision():
    pts, gt = pcl_dacpo.make_scene("box", 4000, seed=4)
    moved = pts.astype(np.float64) + np.array([4.5e5, 5.4e6, 120.0])
    a, _ = pcl_dacpo.orient(pts, ipsr_enabled=False)
    b, _ = pcl_dacpo.orient(moved, ipsr_enabled=False)
    assert wrong_up_to_flip(b, gt) < 1.0
    assert np.mean(np.einsum("ij,ij->i", a, b) > 0) > 0.995


# ---- cancel ------------------------------------------------------------------

def test_progress_callback_sees_stages_and_can_cancel():
    pts, _ = pcl_dacpo.make_scene("box", 4000, seed=1)
    seen = []

    def watch(stage, fraction):
        seen.append((stage, fraction))
        return True

    pcl_dacpo.orient(pts, progress=watch, ipsr_enabled=False)
    assert seen and all(0.0 <= f <= 1.0 for _, f in seen)

    def stop(stage, fraction):
        return stage != "segment"

    with pytest.raises(pcl_dacpo.DacpoError) as e:
        pcl_dacpo.orient(pts, progress=stop)
    assert e.value.status == 9  # cancelled

    def boom(stage, fraction):
        raise RuntimeError("from the callback")

    with pytest.raises(RuntimeError, match="from the callback"):
        pcl_dacpo.orient(pts, progress=boom)


# ---- the same answer as the C tool ---------------------------------------------

def write_ply(path, pts):
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
                 "property float x\nproperty float y\nproperty float z\nend_header\n"
                 % len(pts)).encode())
        f.write(np.ascontiguousarray(pts, dtype="<f4").tobytes())


def read_ply_normals(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    n = int(next(l for l in header if l.startswith("element vertex")).split()[2])
    props, element = [], None
    for line in header:  # the vertex element's properties only (PCL adds a camera)
        if line.startswith("element"):
            element = line.split()[1]
        elif line.startswith("property") and element == "vertex":
            props.append(line.split())
    sizes = {"float": 4, "double": 8, "int": 4, "uint": 4, "uchar": 1, "char": 1}
    fmt = "<" + "".join({"float": "f", "double": "d", "int": "i", "uint": "I",
                         "uchar": "B", "char": "b"}[p[1]] for p in props)
    step = sum(sizes[p[1]] for p in props)
    names = [p[2] for p in props]
    rows = [struct.unpack_from(fmt, data, end + i * step) for i in range(n)]
    axes = ("normal_x", "normal_y", "normal_z") if "normal_x" in names else ("nx", "ny", "nz")
    idx = [names.index(c) for c in axes]
    return np.array([[r[i] for i in idx] for r in rows], dtype=np.float32)


@pytest.mark.skipif(not os.environ.get("DACPO_ORIENT_TOOL"), reason="C tool not built")
def test_same_normals_as_the_c_tool(tmp_path):
    pts, _ = pcl_dacpo.make_scene("room", 8000, seed=5)
    write_ply(tmp_path / "room.ply", pts)
    subprocess.run([os.environ["DACPO_ORIENT_TOOL"], str(tmp_path / "room.ply"),
                    str(tmp_path / "out.ply"), "-estimate", "-q", "-seed", "3", "-threads", "1"],
                   check=True, capture_output=True)
    tool = read_ply_normals(tmp_path / "out.ply")
    mine, _ = pcl_dacpo.orient(pts, seed=3, threads=1)
    np.testing.assert_allclose(mine, tool, atol=1e-6)


# ---- many calls --------------------------------------------------------------

def test_no_reference_or_memory_leaks_over_1000_calls():
    pts, _ = pcl_dacpo.make_scene("plane", 200, seed=1)
    normals_in = np.tile(np.array([0, 0, 1], dtype=np.float32), (200, 1))
    refs = (sys.getrefcount(pts), sys.getrefcount(normals_in))
    for _ in range(50):  # warm up allocators
        pcl_dacpo.orient(pts, normals_in, ipsr_enabled=False, threads=1)
    gc.collect()
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    for _ in range(1000):
        out, result = pcl_dacpo.orient(pts, normals_in, ipsr_enabled=False, threads=1)
    del out, result
    gc.collect()
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    assert (sys.getrefcount(pts), sys.getrefcount(normals_in)) == refs
    assert rss1 - rss0 < 20 * 1024  # KiB: a leak of 1 KB per call would show


def test_ctrl_c_cancels_a_long_run_cleanly():
    code = ("import pcl_dacpo, sys\n"
            "pts, _ = pcl_dacpo.make_scene('room', 400000, seed=1)\n"
            "print('ready', flush=True)\n"
            "try:\n"
            "    pcl_dacpo.orient(pts, threads=1)\n"
            "    print('finished')\n"
            "except KeyboardInterrupt:\n"
            "    print('interrupted')\n")
    import signal
    import time
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                         env=dict(os.environ))
    assert p.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    t0 = time.monotonic()
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert out.strip() == "interrupted"
    assert p.returncode == 0
    assert time.monotonic() - t0 < 10.0  # the core stops at its next progress report
