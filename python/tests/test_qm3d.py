"""The qm3d Python package against the qm3d tool: same doubles, every input form, typed errors,
concurrency. Run by ctest (python_tests) with PYTHONPATH set to the build's python/ folder."""

import json
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import qm3d

SHARED = Path(os.environ.get("QM3D_SHARED_DATA_DIR", Path(__file__).resolve().parents[3] / "shared" / "data"))
REF = SHARED / "reference"
SOURCE = Path(os.environ.get("QM3D_SOURCE_DIR", Path(__file__).resolve().parents[2]))
BINARY = os.environ.get("QM3D_BINARY")
SANITIZED = os.environ.get("QM3D_SANITIZED") == "1"

CLOUD_REF = REF / "pcqm" / "sphere_50k_ref.ply"
CLOUD_DIST = REF / "pcqm" / "sphere_50k_cnoise10.ply"
MESH_REF = REF / "cmdm" / "blob4_ref.ply"
MESH_DIST = REF / "cmdm" / "blob4_colnoise.ply"
# The shared reference: MEPP-team/PCQM's value on this pair (tests/pointcloud reference table).
PCQM_REFERENCE_VALUE = 0.012322561648393961


def tool_json(*args):
    """The tool's --json object for the given arguments."""
    if not BINARY:
        pytest.skip("QM3D_BINARY not set (run through ctest)")
    out = subprocess.run([BINARY, *map(str, args), "--json", "--quiet"], check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout)


def without_seconds(d):
    d = dict(d)
    d.pop("seconds", None)
    return d


# ---- the same doubles as the tool ----------------------------------------------------------

@pytest.mark.parametrize("metric,ref,dist,options", [
    ("pcqm", CLOUD_REF, CLOUD_DIST, {}),
    ("pcqm", CLOUD_REF, REF / "pcqm" / "sphere_50k_down0.5.ply", {"knn": 10}),
    ("cmdm", MESH_REF, MESH_DIST, {}),
    ("cmdm", REF / "cmdm" / "blob4_ref.off", REF / "cmdm" / "blob4_bothnoise.off",
     {"direction": "dist-to-ref"}),
    ("msdm2", REF / "cmdm" / "blob4_ref.obj", REF / "cmdm" / "blob4_geonoise.obj", {"scales": 2}),
])
def test_scores_equal_the_tool_exactly(metric, ref, dist, options):
    args = []
    for k, v in options.items():
        args += [f"--{k}", v]
    expected = tool_json(metric, ref, dist, *args)
    result = qm3d.metric(metric, str(ref), str(dist), **options)
    assert result.score == expected["score"]  # the same double, not close
    assert without_seconds(result.to_dict()) == without_seconds(expected)


def test_pcqm_gives_the_reference_value():
    r = qm3d.pcqm(str(CLOUD_REF), str(CLOUD_DIST))
    assert r.score == pytest.approx(PCQM_REFERENCE_VALUE, rel=1e-9)
    assert r.ref_to_dist is not None and r.dist_to_ref is None
    assert set(r.features) == {f"F{k}" for k in range(1, 9)}
    assert r.features == r.ref_to_dist.features


def test_compare_runs_every_metric_that_applies():
    meshes = qm3d.compare(str(REF / "cmdm" / "blob4_ref.off"), str(REF / "cmdm" / "blob4_colnoise.off"),
                          points=2000)
    assert list(meshes) == ["cmdm", "msdm2", "pcqm", "pcqm_sampled", "dlab"]
    # The files are read once for all five and freed by the last: each score is the metric's own.
    for name, result in meshes.items():
        alone = qm3d.metric(name, str(REF / "cmdm" / "blob4_ref.off"),
                            str(REF / "cmdm" / "blob4_colnoise.off"),
                            **({"points": 2000} if name == "pcqm_sampled" else {}))
        assert result.score == alone.score, name
    clouds = qm3d.compare(CLOUD_REF, CLOUD_DIST)
    assert list(clouds) == ["pcqm", "psnr", "dlab"]
    assert clouds["pcqm"].score == qm3d.pcqm(CLOUD_REF, CLOUD_DIST).score
    assert clouds["psnr"].score == qm3d.psnr(CLOUD_REF, CLOUD_DIST).score
    assert clouds["dlab"].score == qm3d.dlab(CLOUD_REF, CLOUD_DIST).score


# ---- arrays, files and Open3D objects give identical scores -------------------------------

def test_cloud_arrays_files_and_open3d_give_identical_scores():
    file_score = qm3d.pcqm(CLOUD_REF, CLOUD_DIST).score
    ref, dist = qm3d.read_cloud(CLOUD_REF), qm3d.read_cloud(CLOUD_DIST)
    assert ref["positions"].shape == (50000, 3) and ref["colors"].dtype == np.float64
    assert qm3d.pcqm((ref["positions"], ref["colors"]), dist).score == file_score
    as_bytes = (np.round(dist["colors"] * 255).astype(np.uint8))
    assert qm3d.pcqm(ref, {"positions": dist["positions"], "colors": as_bytes}).score == file_score
    o3d = pytest.importorskip("open3d")
    o_ref, o_dist = o3d.io.read_point_cloud(str(CLOUD_REF)), o3d.io.read_point_cloud(str(CLOUD_DIST))
    assert qm3d.pcqm(o_ref, o_dist).score == file_score


def test_mesh_arrays_files_and_open3d_give_identical_scores():
    file_result = qm3d.cmdm(MESH_REF, MESH_DIST, per_element=True)
    ref, dist = qm3d.read_mesh(MESH_REF), qm3d.read_mesh(MESH_DIST)
    assert ref["faces"].dtype == np.uint32 and ref["faces"].shape[1] == 3
    arrays = qm3d.cmdm((ref["positions"], ref["colors"], ref["faces"]),
                       (dist["positions"], dist["colors"], dist["faces"].astype(np.int64)),
                       per_element=True)
    assert arrays.score == file_result.score
    assert np.array_equal(arrays.dist_to_ref.per_element, file_result.dist_to_ref.per_element)
    o3d = pytest.importorskip("open3d")
    o_ref, o_dist = o3d.io.read_triangle_mesh(str(MESH_REF)), o3d.io.read_triangle_mesh(str(MESH_DIST))
    assert qm3d.cmdm(o_ref, o_dist).score == file_result.score


def test_per_element_values_and_the_single_direction():
    r = qm3d.pcqm(CLOUD_REF, CLOUD_DIST, per_element=True)
    assert r.per_element.shape == (50000,)
    assert r.per_element.mean() == pytest.approx(r.score, rel=1e-12)
    assert qm3d.pcqm(CLOUD_REF, CLOUD_DIST).per_element is None
    both = qm3d.pcqm(CLOUD_REF, CLOUD_DIST, direction="symmetric")
    assert set(both.directions) == {"dist_to_ref", "ref_to_dist"}
    assert both.features is None
    assert both.score == (both.dist_to_ref.score + both.ref_to_dist.score) / 2


def test_options_models_and_progress():
    default = qm3d.cmdm(MESH_REF, MESH_DIST)
    model = qm3d.load_model(SOURCE / "data" / "models" / "cmdm.json")
    assert qm3d.cmdm(MESH_REF, MESH_DIST, model=model).score == pytest.approx(default.score, rel=1e-12)
    chroma = qm3d.cmdm(MESH_REF, MESH_DIST, weights=[0, 0, 0, 0, 0, 0, 1, 0])
    assert chroma.score == pytest.approx(chroma.to_dict()["directions"]["dist_to_ref"]["features"]["f7"] / 2
                                         + chroma.to_dict()["directions"]["ref_to_dist"]["features"]["f7"] / 2)
    stages = []
    qm3d.msdm2(MESH_REF, MESH_DIST, scales=1, progress=lambda stage, f: stages.append((stage, f)))
    assert stages and stages[0][1] == 0.0
    assert qm3d.pcqm(CLOUD_REF, CLOUD_DIST, radius=0.01).score != qm3d.pcqm(CLOUD_REF, CLOUD_DIST).score


def test_sample_and_read():
    a = qm3d.sample(MESH_REF, points=500, seed=3)
    b = qm3d.sample(qm3d.read_mesh(MESH_REF), points=500, seed=3)
    assert a["positions"].shape == (500, 3)
    assert np.array_equal(a["positions"], b["positions"]) and np.array_equal(a["colors"], b["colors"])
    with pytest.raises(ValueError):
        qm3d.sample(MESH_REF)


def test_evaluate_matches_numpy():
    rng = np.random.default_rng(1)
    scores = rng.random(40)
    mos = 5 - 4 * scores + rng.normal(0, 0.2, 40)
    e = qm3d.evaluate(scores, mos, bootstrap=50)
    assert e["stimuli"] == 40
    assert e["statistics"]["plcc"]["value"] == pytest.approx(np.corrcoef(scores, mos)[0, 1], rel=1e-12)
    low, high = e["statistics"]["srocc"]["ci95"]
    assert low <= e["statistics"]["srocc"]["value"] <= high
    with pytest.raises(ValueError, match="scores and mos"):
        qm3d.evaluate([1, 2], [1, 2, 3])


# ---- bad input: typed errors naming the argument, never a crash ---------------------------

@pytest.mark.parametrize("bad,message", [
    ((np.zeros((5, 2)), np.zeros((5, 3))), "positions: expected shape \\(N, 3\\)"),
    ((np.zeros((5, 3)), np.zeros((4, 3))), "colors: 4 rows for 5 positions"),
    ((np.zeros((5, 3)), np.full((5, 3), 2.0)), "colors: row 0 has 2.0+, outside 0-1"),
    ((np.zeros((5, 3)), np.zeros((5, 3), dtype=np.int16)), "colors: expected uint8"),
    ((np.array([[0, 0, np.nan]] * 5), np.zeros((5, 3))), "positions: row 0 is not finite"),
    ((np.array([["a", "b", "c"]]), np.zeros((1, 3))), "positions: expected a float array"),
    ((np.zeros((3, 3)), np.zeros((3, 3)), np.array([[0, 1, 3]])), "faces: row 0 refers to vertex 3"),
    ((np.zeros((3, 3)), np.zeros((3, 3)), np.array([[0.0, 1, 2]])), "faces: expected an integer array"),
    ({"points": np.zeros((3, 3))}, "a dict needs 'positions'"),
])
def test_bad_arrays_raise_value_error_naming_the_argument(bad, message):
    good = (np.random.default_rng(0).random((30, 3)), np.full((30, 3), 0.5))
    metric = qm3d.cmdm if (isinstance(bad, tuple) and len(bad) == 3) else qm3d.pcqm
    with pytest.raises(ValueError, match="distorted: " + message):
        metric(good if metric is qm3d.pcqm else (np.eye(3), np.full((3, 3), 0.5), np.array([[0, 1, 2]])),
               bad)


def test_bad_files_and_options_raise_typed_errors(tmp_path):
    with pytest.raises(qm3d.InputError) as missing:
        qm3d.pcqm(tmp_path / "missing.ply", CLOUD_DIST)
    assert isinstance(missing.value, OSError) and "missing.ply" in str(missing.value)
    broken = tmp_path / "broken.ply"
    broken.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\n")
    with pytest.raises(qm3d.FormatError) as malformed:
        qm3d.pcqm(broken, CLOUD_DIST)
    assert isinstance(malformed.value, ValueError) and "broken.ply" in str(malformed.value)
    with pytest.raises(ValueError, match="scales"):
        qm3d.cmdm(MESH_REF, MESH_DIST, scales=0)
    with pytest.raises(ValueError, match="knn: expected an integer"):
        qm3d.pcqm(CLOUD_REF, CLOUD_DIST, knn=2.5)
    # A string where a number is expected is a ValueError naming the option, for a number, a
    # list of numbers and the weights alike (a second _finite once shadowed the scalar one).
    with pytest.raises(ValueError, match="radius: expected a number"):
        qm3d.pcqm(CLOUD_REF, CLOUD_DIST, radius="0.004")
    with pytest.raises(ValueError, match="rotation: expected a number"):
        qm3d.ibsm(CLOUD_REF, CLOUD_DIST, rotation=["x", 0, 0])
    with pytest.raises(ValueError, match="weights: expected a number"):
        qm3d.pcqm(CLOUD_REF, CLOUD_DIST, weights=["1"] * 8)
    with pytest.raises(TypeError, match="unexpected keyword argument 'radiuss'"):
        qm3d.pcqm(CLOUD_REF, CLOUD_DIST, radiuss=0.1)
    with pytest.raises(ValueError, match="direction"):
        qm3d.pcqm(CLOUD_REF, CLOUD_DIST, direction="both")
    with pytest.raises(TypeError):
        qm3d.pcqm(42, CLOUD_DIST)
    with pytest.raises(qm3d.FormatError, match="no faces"):
        qm3d.msdm2(CLOUD_REF, CLOUD_DIST)
    with pytest.raises(ValueError, match="cmdm"):
        qm3d.cmdm(MESH_REF, MESH_DIST, model=qm3d.load_model(SOURCE / "data" / "models" / "pcqm.json"))


# ---- the GIL is released -------------------------------------------------------------------

def test_two_threads_score_two_pairs_like_one_after_the_other():
    # Concurrent calls give the sequential results (the GIL itself: test_hostile_python.py).
    pairs = [(CLOUD_REF, CLOUD_DIST), (CLOUD_DIST, CLOUD_REF)]
    run = lambda pair: qm3d.pcqm(*pair, threads=1, radius=0.008).score
    sequential = [run(p) for p in pairs]
    with ThreadPoolExecutor(2) as pool:
        assert list(pool.map(run, pairs)) == sequential
