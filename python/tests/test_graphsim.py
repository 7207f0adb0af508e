"""qm3d.graphsim / qm3d.msgraphsim (issue 42) against the reference data
../shared/data/reference/graphsim (the authors' MATLAB functions run in float64 under Octave):
every float64 column of every case within 1e-10 relative, a cloud against itself exactly 1,
numpy arrays scored as their files, and bad inputs refused naming the file or the cause.
"""

import csv
import os

import numpy as np
import pytest

import qm3d

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
SHARED = os.environ.get("QM3D_SHARED_DATA_DIR") or os.path.join(ROOT, "..", "shared", "data")
DATA = os.path.join(SHARED, "reference", "graphsim")
RTOL = 1e-10

pytestmark = pytest.mark.skipif(not os.path.isdir(DATA), reason="no reference data")


def cases():
    with open(os.path.join(DATA, "graphsim_reference.csv")) as f:
        return list(csv.DictReader(f, delimiter=";"))


def inputs(case):
    return (os.path.join(DATA, case["reference"]), os.path.join(DATA, case["distorted"]),
            os.path.join(DATA, case["keypoint_file"]))


def close(got, want):
    return abs(got - float(want)) <= RTOL * abs(float(want))


@pytest.mark.parametrize("case", cases(), ids=lambda c: c["case"])
def test_every_column_of_the_reference_table(case):
    ref, dist, keys = inputs(case)
    g = qm3d.graphsim(ref, dist, keypoint_file=keys, per_element=True)
    assert close(g.score, case["graphsim"]), g.score
    assert len(g.per_element) == int(case["n_keypoints"])
    assert g.details["epsilon"] == float(case["epsilon"])
    assert close(qm3d.graphsim(ref, dist, keypoint_file=keys, pooling_weights=[1, 1, 1]).score,
                 case["graphsim_w111"])
    assert close(qm3d.graphsim(ref, dist, keypoint_file=keys, threshold=0.01).score,
                 case["graphsim_T0.01"])
    assert close(qm3d.msgraphsim(ref, dist, keypoint_file=keys).score, case["msgraphsim"])
    ms6 = qm3d.msgraphsim(ref, dist, keypoint_file=keys, scales=6)
    assert close(ms6.score, case["msgraphsim_ns6"])
    for k in range(6):
        assert close(ms6.features[f"scale{k}"], case[f"ms_scale{k}"]), k
    assert ms6.features["scale0"] == g.score


def test_self_is_exactly_one_and_arrays_score_as_their_files():
    case = next(c for c in cases() if c["case"] == "smA_cnoise8")
    ref, dist, keys = inputs(case)
    assert qm3d.graphsim(ref, ref, keypoint_file=keys).score == 1.0
    assert qm3d.msgraphsim(ref, ref, keypoint_file=keys, scales=6).score == 1.0
    import pathlib
    assert (qm3d.graphsim(ref, dist, keypoint_file=pathlib.Path(keys)).score
            == qm3d.graphsim(ref, dist, keypoint_file=keys).score)
    arrays = [qm3d.read_cloud(p) for p in (ref, dist)]
    from_arrays = qm3d.graphsim(*arrays, keypoint_file=keys)
    assert from_arrays.score == qm3d.graphsim(ref, dist, keypoint_file=keys).score


def test_registered_as_similarities_with_the_tool_options():
    specs = {m["name"]: m for m in qm3d.metrics()}
    for name in ("graphsim", "msgraphsim"):
        assert specs[name]["higher_is_better"]
        options = {o["name"]: o["default"] for o in specs[name]["options"]}
        assert options["keypoint_file"] == "" and options["threshold"] == 0.001
        assert options["pooling_weights"] == [6, 1, 1]
    assert {o["name"]: o["default"] for o in specs["msgraphsim"]["options"]}["scales"] == 3
    with pytest.raises(TypeError):
        qm3d.graphsim("a.ply", "b.ply", scales=3)


def test_seeded_keypoints_are_reproducible():
    case = next(c for c in cases() if c["case"] == "smA_cshift")
    ref, dist, _ = inputs(case)
    a = qm3d.graphsim(ref, dist, keypoints=20, seed=3, threads=1)
    b = qm3d.graphsim(ref, dist, keypoints=20, seed=3, threads=2)
    assert a.details["keypoint_rows"] == b.details["keypoint_rows"]
    assert a.score == b.score
    assert len(a.details["keypoint_rows"]) == 20


def test_bad_inputs_name_the_file_or_the_cause(tmp_path):
    case = next(c for c in cases() if c["case"] == "smA_ref")
    ref, _, _ = inputs(case)
    keys = tmp_path / "keys.txt"
    keys.write_text("1\n9048\n")
    with pytest.raises(qm3d.FormatError, match="keys.txt: line 2: keypoint index 9048 is out"):
        qm3d.graphsim(ref, ref, keypoint_file=str(keys))
    positions = np.array([[x, y, x % 20] for x in range(30) for y in range(30)], dtype=float)
    colours = np.full((len(positions), 3), 128, dtype=np.uint8)
    plain = tmp_path / "plain.ply"
    plain.write_text(f"ply\nformat ascii 1.0\nelement vertex {len(positions)}\n"
                     "property float x\nproperty float y\nproperty float z\nend_header\n"
                     + "".join(f"{x} {y} {z}\n" for x, y, z in positions))
    with pytest.raises(qm3d.FormatError, match="plain.ply: no vertex colours"):
        qm3d.msgraphsim(ref, str(plain))
    flat = positions.copy()
    flat[:, 2] = 0
    with pytest.raises(qm3d.NumericError, match="neighbourhood radius"):
        qm3d.graphsim((flat, colours), (flat, colours))
