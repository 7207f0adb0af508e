"""qm3d.psnr on two meshes and qm3d.sample(mode="grid") against MPEG mmetric 1.1.7 (issue 28):
every value of every case of mm_pcc_reference.csv but the G 1024 one (1.9M samples per mesh;
bench/run_benchmarks.sh psnr_mesh checks it) within 1e-8 relative, with test_psnr.py's rules,
and mmetric's own sampled clouds point for point.
"""

import csv
import os

import numpy as np
import pytest

import qm3d
from test_psnr import SHARED, expect_values

TABLE = os.path.join(SHARED, "reference", "mpeg", "mm_pcc_reference.csv")
SAMPLED = os.path.join(SHARED, "reference", "mpeg", "sampled")


def cases():
    with open(TABLE, newline="") as f:
        return [c for c in csv.DictReader(f, delimiter=";") if c["case"] != "mm_pcc_monkey_g1024"]


def options(case):
    """The case's mmetric options as qm3d.psnr keywords."""
    args = case["compare_args"].split()
    out = {"grid_size": int(case["gridSize"])}
    for i, a in enumerate(args):
        value = a.split("=", 1)[1] if "=" in a else (args[i + 1] if i + 1 < len(args) else "")
        if a == "--resolution" and value != "0":
            out["peak"] = float(value)
        elif a.startswith("--normalCalcModificationEnable") and value == "false":
            out["d2_normals"] = "transferred"
        elif a == "--dropDuplicates":
            out["drop_duplicates"] = int(value)
        elif a == "--neighborsProc":
            out["neighbours"] = int(value)
    return out


@pytest.mark.parametrize("case", cases(), ids=lambda c: c["case"])
def test_every_mmetric_mesh_case(case):
    r = qm3d.psnr(os.path.join(SHARED, case["mesh_a"]), os.path.join(SHARED, case["mesh_b"]),
                  **options(case))
    expect_values(case, r)
    assert r.details["peak"] == pytest.approx(float(case["peak"]), rel=1e-8)
    assert r.details["sampling"]["reference"]["samples"] == int(case["nA_sampled"])
    assert r.details["sampling"]["distorted"]["samples"] == int(case["nB_sampled"])
    assert r.details["points_reference"] == int(case["nA"])
    assert r.details["points_distorted"] == int(case["nB"])


def read_ascii_ply(path):
    with open(path) as f:
        while f.readline().strip() != "end_header":
            pass
        rows = np.loadtxt(f, dtype=np.float64)
    return rows[:, 0:3].astype(np.float32), rows[:, 3:6].astype(np.float32), rows[:, 6:9]


def test_grid_samples_equal_mmetrics():
    a = os.path.join(SHARED, "reference", "cmdm", "blob4_ref.ply")
    box = (-0.997778773, -1.05314529, -1.04921687, 1.05481851, 1.04963803, 1.05762815)
    s = qm3d.sample(a, mode="grid", grid_size=100, box=box)
    p, n, c = read_ascii_ply(os.path.join(SAMPLED, "blob4_ref_g100.ply"))
    assert len(s["positions"]) == 24261
    np.testing.assert_array_equal(s["positions"].astype(np.float32), p)
    np.testing.assert_array_equal(s["normals"].astype(np.float32), n)
    np.testing.assert_array_equal(np.rint(s["colors"] * 255), c)


def test_grid_sample_arguments_are_checked():
    a = os.path.join(SHARED, "reference", "cmdm", "blob4_ref.ply")
    with pytest.raises(ValueError):
        qm3d.sample(a, mode="grid", points=10)
    with pytest.raises(ValueError):
        qm3d.sample(a, mode="hexagonal")
    with pytest.raises(ValueError):
        qm3d.sample(a, mode="grid", box=(0, 0, 0))
