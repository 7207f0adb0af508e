"""qm3d.psnr against MPEG pc_error 0.14.2's reference table (issue 25): every value of every case
within 1e-8 relative, with the rules of tests/mpeg_reference.h (inf as float("inf"); pc_error's
zero Hausdorff, printed DBL_MIN, is 0 with an infinite PSNR; an empty field is a value left out).
"""

import csv
import math
import os

import numpy as np
import pytest

import qm3d

SHARED = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data")
TABLE = os.path.join(SHARED, "reference", "mpeg", "pc_error_reference.csv")
ZERO_HAUSDORFF = "2.22507386e-308"
COLUMNS = ["d1_mse", "d1_psnr", "d2_mse", "d2_psnr", "d1_haus", "d1_haus_psnr", "d2_haus",
           "d2_haus_psnr", "c0_mse", "c1_mse", "c2_mse", "c0_psnr", "c1_psnr", "c2_psnr",
           "c0_haus", "c1_haus", "c2_haus", "c0_haus_psnr", "c1_haus_psnr", "c2_haus_psnr"]


def cases():
    with open(TABLE, newline="") as f:
        return list(csv.DictReader(f, delimiter=";"))


def options(case):
    """The case's pc_error options as qm3d.psnr keywords."""
    args = case["args"].split()
    out = {}
    for i, a in enumerate(args):
        value = a.split("=", 1)[1] if "=" in a else (args[i + 1] if i + 1 < len(args) else "")
        if a == "-r":
            out["peak"] = float(value)
        elif a == "-n":
            out["normals"] = os.path.join(SHARED, value)
        elif a.startswith("--dropdups="):
            out["drop_duplicates"] = int(value)
        elif a.startswith("--neighborsProc="):
            out["neighbours"] = int(value)
        elif a.startswith("--averageNormals="):
            out["average_normals"] = value != "0"
        elif a.startswith("--mseSpace="):
            out["color_space"] = {"0": "rgb", "1": "ycbcr", "8": "ycocg"}[value]
    return out


def expect(case, column, got):
    printed = case[column]
    where = f"{case['case']} {column} (pc_error {printed})"
    if printed == "":
        assert got is None, f"{where}: qm3d gives {got}"
        return
    assert got is not None, f"{where}: qm3d leaves it out"
    if column.endswith("_haus_psnr") and case[column[:-5]] == ZERO_HAUSDORFF:
        assert got == math.inf, where
    elif printed == ZERO_HAUSDORFF:
        assert got == 0.0, where
    elif printed == "inf":
        assert got == math.inf, where
    else:
        expected = float(printed)
        assert abs(got - expected) <= 1e-8 * abs(expected), f"{where}: {got!r}"


def expect_values(case, r):
    """Every AB_/BA_/sym_ value of a table row in a psnr result."""
    for column in COLUMNS:
        name = column.replace("haus", "hausdorff")
        expect(case, "AB_" + column, r.ref_to_dist.features.get(name))
        expect(case, "BA_" + column, r.dist_to_ref.features.get(name))
        expect(case, "sym_" + column, r.features.get(name))


@pytest.mark.parametrize("case", cases(), ids=lambda c: c["case"])
def test_every_pc_error_case(case):
    r = qm3d.psnr(os.path.join(SHARED, case["a"]), os.path.join(SHARED, case["b"]),
                  **options(case))
    expect_values(case, r)
    assert r.details["peak"] == pytest.approx(float(case["peak"]), rel=1e-8)
    assert r.details["points_reference"] == int(case["nA"])
    assert r.details["points_distorted"] == int(case["nB"])
    assert r.score == r.features["d1_psnr"]


def test_registry_says_psnr_is_a_quality_with_named_values():
    spec = next(s for s in qm3d.metrics() if s["name"] == "psnr")
    assert spec["higher_is_better"] is True
    assert "d1_psnr" in spec["value_names"]
    assert spec["quality_value_names"] == [n for n in spec["value_names"] if n.endswith("_psnr")]
    assert "d1_mse" not in spec["quality_value_names"]
    assert all(s["higher_is_better"] is (s["name"] in ("psnr", "ibsm", "graphsim", "msgraphsim",
                                                     "pointssim", "geodesicpsim"))
               for s in qm3d.metrics())
    assert {o["name"] for o in spec["options"]} >= {
        "peak", "color_space", "drop_duplicates", "neighbours", "average_normals", "normals",
        "no_hausdorff", "no_color"}


def test_per_element_is_the_d1_error_of_each_input_point():
    ref = os.path.join(SHARED, "reference", "mpeg", "vox1_ref_n.ply")
    dist = os.path.join(SHARED, "reference", "voxel", "vox1_requant8.ply")
    r = qm3d.psnr(ref, dist, peak=1023, per_element=True)
    d = r.ref_to_dist.per_element
    assert d.shape == (r.details["points_reference"],)
    assert np.mean(d) == pytest.approx(r.ref_to_dist.features["d1_mse"], rel=1e-12)
    assert np.max(d) == pytest.approx(r.ref_to_dist.features["d1_hausdorff"], rel=0)
    assert r.box_size is None and r.ref_to_dist.box_size is None
    extra = r.ref_to_dist.per_element_values
    assert set(extra) == {"d2", "c0", "c1", "c2"}
    assert np.mean(extra["c0"]) == pytest.approx(r.ref_to_dist.features["c0_mse"], rel=1e-12)
    assert np.mean(extra["d2"]) == pytest.approx(r.ref_to_dist.features["d2_mse"], rel=1e-12)


def test_identical_clouds_are_infinite_and_json_null():
    ref = os.path.join(SHARED, "reference", "mpeg", "vox1_ref_n.ply")
    r = qm3d.psnr(ref, ref)
    assert r.score == math.inf
    assert r.features["d1_hausdorff"] == 0.0
    assert r.to_dict()["features"]["d1_psnr"] is None
    assert ",inf," in r.csv_row()


def test_bad_input_names_the_file(tmp_path):
    plain = tmp_path / "plain.ply"
    plain.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                     "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n")
    ref = os.path.join(SHARED, "reference", "mpeg", "vox1_ref_n.ply")
    with pytest.raises(qm3d.FormatError, match="plain.ply: no vertex colours"):
        qm3d.psnr(ref, str(plain), peak=1)
    with pytest.raises(qm3d.FormatError, match="plain.ply: no normals"):
        qm3d.psnr(ref, ref, normals=str(plain))
