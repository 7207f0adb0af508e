"""qm3d.pointssim (PointSSIM, issue 41): every value of the reference table
(../shared/data/reference/pointssim/pointssim_reference.csv, mmspg/pointssim under Octave) within
1e-10 relative or 1e-13 absolute (the voxel crops on geometry and colour only: their normal and
curvature columns depend on the solver, the data set's README), from files, numpy arrays and
Open3D clouds alike; identity exactly 1; bad input naming the file.
"""

import csv
import os

import numpy as np
import pytest

import qm3d

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
SHARED = os.environ.get("QM3D_SHARED_DATA_DIR") or os.path.join(ROOT, "..", "shared", "data")
DIR = os.path.join(SHARED, "reference", "pointssim")
ALL = dict(estimators="all", poolings="all", attributes="all")


def rows():
    with open(os.path.join(DIR, "pointssim_reference.csv")) as f:
        return list(csv.DictReader(f))


def fit_of(row):
    size = row["fit_size"]
    return {"fit_knn": int(size)} if row["fit_method"] == "knn" else {"fit_radius": float(size)}


def check(row, result):
    voxel = row["fileA"].startswith("vox")
    where = {"BA": result.dist_to_ref.features, "AB": result.ref_to_dist.features,
             "Sym": result.features}
    checked = 0
    for column, text in row.items():
        parts = column.split("_")
        if len(parts) != 4 or parts[0] not in ("geom", "norm", "curv", "color"):
            continue
        if voxel and parts[0] in ("norm", "curv"):
            continue
        expected = float(text)
        got = where[parts[3]]["_".join(parts[:3]).lower()]
        assert abs(got - expected) <= max(1e-13, 1e-10 * abs(expected)), (column, got, expected)
        checked += 1
    assert checked == (126 if voxel else 252)


@pytest.mark.parametrize("row", rows(), ids=lambda r: r["case"] + "_K" + r["K"])
def test_every_reference_value(row):
    r = qm3d.pointssim(os.path.join(DIR, row["fileA"]), os.path.join(DIR, row["fileB"]),
                       neighbours=int(row["K"]), **fit_of(row), **ALL, per_element=True)
    check(row, r)
    assert r.details["points"] == {"reference": int(row["nA"]), "distorted": int(row["nB"])}
    assert r.ref_to_dist.per_element.shape == (int(row["nA_in"]),)


def test_arrays_and_open3d_give_the_files_values():
    o3d = pytest.importorskip("open3d")
    row = next(r for r in rows() if r["case"] == "S07" and r["K"] == "12")  # duplicates fused
    a, b = (o3d.io.read_point_cloud(os.path.join(DIR, row[k])) for k in ("fileA", "fileB"))
    assert len(a.points) == int(row["nA_in"]) and len(b.points) == int(row["nB_in"])
    from_open3d = qm3d.pointssim(a, b, neighbours=12, **fit_of(row), **ALL)
    check(row, from_open3d)
    arrays = [(np.asarray(c.points), np.round(np.asarray(c.colors) * 255).astype(np.uint8))
              for c in (a, b)]
    from_arrays = qm3d.pointssim(*arrays, neighbours=12, **fit_of(row), **ALL)
    assert from_arrays.features == from_open3d.features
    files = qm3d.pointssim(os.path.join(DIR, row["fileA"]), os.path.join(DIR, row["fileB"]),
                           neighbours=12, **fit_of(row), **ALL)
    assert files.features == from_open3d.features
    # Without colours (colors None, an Open3D cloud without colours): geometry, normals, curvature.
    plain = qm3d.pointssim((arrays[0][0], None), (arrays[1][0], None), fit_knn=12)
    assert sorted(plain.features) == ["curv_var_mean", "geom_var_mean", "norm_var_mean"]
    assert plain.score == plain.features["geom_var_mean"] == files.features["geom_var_mean"]
    b.colors = o3d.utility.Vector3dVector()
    assert qm3d.pointssim(a, b, fit_knn=12).score == plain.score
    with pytest.raises(qm3d.FormatError, match="no vertex colours"):
        qm3d.pcqm(a, b)


def test_identity_is_exactly_one_and_the_score_is_colour_variance():
    path = os.path.join(DIR, "sphere_2k_ref.ply")
    r = qm3d.pointssim(path, path, fit_knn=12, **ALL)
    assert r.score == 1.0
    assert set(r.features.values()) == {1.0} and len(r.features) == 84
    dist = os.path.join(DIR, "sphere_2k_cnoise30.ply")
    d = qm3d.pointssim(path, dist, fit_knn=12)
    assert sorted(d.features) == ["color_var_mean", "curv_var_mean", "geom_var_mean",
                                  "norm_var_mean"]
    assert d.score == d.features["color_var_mean"] < 1
    assert d.score == min(d.ref_to_dist.score, d.dist_to_ref.score)


def test_registry_entry():
    spec = next(s for s in qm3d.metrics() if s["name"] == "pointssim")
    assert spec["higher_is_better"] is True
    assert len(spec["value_names"]) == 84 and spec["quality_value_names"] == spec["value_names"]
    assert {o["name"] for o in spec["options"]} == {
        "neighbours", "fit_knn", "fit_radius", "estimators", "poolings", "attributes"}


def test_bad_input_names_the_file(tmp_path):
    plain = tmp_path / "plain.ply"
    points = "".join(f"{i % 5} {i // 5} {(i * 7) % 3}\n" for i in range(40))
    plain.write_text("ply\nformat ascii 1.0\nelement vertex 40\nproperty float x\n"
                     "property float y\nproperty float z\nend_header\n" + points)
    ref = os.path.join(DIR, "sphere_2k_ref.ply")
    with pytest.raises(qm3d.FormatError, match="plain.ply: no colours"):
        qm3d.pointssim(ref, str(plain), fit_knn=12, attributes="color")
    tiny = tmp_path / "tiny.ply"
    tiny.write_text("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n")
    with pytest.raises(qm3d.NumericError, match="tiny.ply: 4 distinct points"):
        qm3d.pointssim(str(plain), str(tiny), fit_knn=6, neighbours=3)
    with pytest.raises(ValueError, match="estimators: unknown name 'nope'"):
        qm3d.pointssim(ref, ref, fit_knn=12, estimators="var,nope")
    with pytest.raises(ValueError, match="default fit radius"):
        qm3d.pointssim(ref, ref)
