"""qm3d.geodesicpsim (issue 43): every row of the GeodesicPSIM reference table within 1e-9, the
keypoints' values with per_element=True, and bad input refused naming the file.
"""

import csv
import gzip
import os
import shutil

import numpy as np
import pytest

import qm3d
from test_psnr import SHARED

DATA = os.path.join(SHARED, "reference", "geodesicpsim")


def rows():
    with open(os.path.join(DATA, "geodesicpsim_reference.csv"), newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """The case inputs in a scratch folder: OBJ gunzipped, MTL and PNG linked."""
    out = tmp_path_factory.mktemp("geodesicpsim")
    src = os.path.join(DATA, "inputs")
    for name in os.listdir(src):
        if name.endswith(".gz"):
            with gzip.open(os.path.join(src, name), "rb") as a, open(out / name[:-3], "wb") as b:
                shutil.copyfileobj(a, b)
        else:
            os.symlink(os.path.join(src, name), out / name)
    return out


@pytest.mark.parametrize("row", rows(), ids=lambda r: r["case"])
def test_reference_row(row, inputs):
    kw = {} if row["N_arg"] == "default" else {"keypoints": int(row["N_arg"])}
    res = qm3d.geodesicpsim(str(inputs / row["ref_obj"]), str(inputs / row["dis_obj"]), **kw)
    assert res.score == pytest.approx(float(row["score"]), rel=1e-9, abs=0)
    for name in ("pcs", "dmc", "pca", "pcv"):
        assert res.features[name] == pytest.approx(float(row[name]), rel=1e-9, abs=0), name
    assert res.details["keypoints"] == int(row["N_used"])
    for name in ("flag1", "flag2", "flag3", "effective_patches"):
        assert res.details[name] == int(row[name]), name
    assert res.details["subdivided"] == row["subdivided"]


def test_keypoint_values_and_threads(inputs):
    ref, dis = str(inputs / "tblob4_ref.obj"), str(inputs / "tblob4_geonoise2.obj")
    one = qm3d.geodesicpsim(ref, dis, keypoints=200, threads=1, per_element=True)
    two = qm3d.geodesicpsim(ref, dis, keypoints=200, threads=2, per_element=True)
    assert one.score == two.score
    d = one.directions["ref_to_dist"]
    assert d.element_positions.shape == (one.details["effective_patches"], 3)
    np.testing.assert_array_equal(d.per_element, two.directions["ref_to_dist"].per_element)
    assert set(d.per_element_values) == {"flag", "pcs", "dmc", "pca", "pcv"}
    assert np.all(d.per_element <= 1.0)


def test_identical_meshes_score_one(inputs):
    ref = str(inputs / "tblob4_ref.obj")
    assert qm3d.geodesicpsim(ref, ref, keypoints=100).score == 1.0


def test_untextured_mesh_names_the_file(inputs, tmp_path):
    plain = tmp_path / "plain.obj"
    plain.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(qm3d.FormatError, match="plain.obj"):
        qm3d.geodesicpsim(str(inputs / "tblob4_ref.obj"), str(plain))
