"""qm3d.ibsm and qm3d.render (issue 27): mmetric's rotated 1024² IBSM case within 1e-6, the
views as numpy arrays (the same images the metric scored, on any thread count), a mesh against
a cloud given as arrays, and bad requests refused.
"""

import csv
import os

import numpy as np
import pytest

import qm3d
from test_psnr import SHARED

TABLE = os.path.join(SHARED, "reference", "mpeg", "mm_ibsm_reference.csv")
MONKEY = os.path.join(SHARED, "reference", "cmdm", "monkey2.obj")
SIMPLIFIED = os.path.join(SHARED, "reference", "cmdm", "monkey_simplified.obj")


def row(name):
    with open(TABLE, newline="") as f:
        return next(r for r in csv.DictReader(f, delimiter=";") if r["case"] == name)


def test_mmetric_rotated_case():
    r = row("mm_ibsm_monkey_r1024_c6_rot")
    res = qm3d.ibsm(MONKEY, SIMPLIFIED, resolution=1024, views=6, rotation=[30, 60, 45],
                    no_ssim=True)
    features = res.directions["dist_to_ref"].features
    checked = 0
    for column, text in r.items():
        name = column.lower()
        if name == "unmatchedpixelpercentage":
            name = "unmatched_pixel_percentage"
        if name not in features:
            continue
        assert features[name] == pytest.approx(float(text), rel=1e-6), column
        checked += 1
    assert checked == 19
    assert res.score == features["yuv_psnr"]


def test_render_gives_the_scored_images():
    res = qm3d.ibsm(MONKEY, SIMPLIFIED, resolution=200, views=4, save_views="")
    d = res.to_dict()
    frame = d["bsphere_center"] + [d["bsphere_radius"]]
    one = qm3d.render(SIMPLIFIED, resolution=200, views=4, frame=frame, threads=1)
    two = qm3d.render(SIMPLIFIED, resolution=200, views=4, frame=frame, threads=2)
    assert len(one["views"]) == 4
    for a, b, scored in zip(one["views"], two["views"], d["views"]):
        assert a["rgb"].shape == (200, 200, 3) and a["rgb"].dtype == np.uint8
        assert a["mask"].dtype == bool and a["depth"].dtype == np.float32
        np.testing.assert_array_equal(a["rgb"], b["rgb"])
        np.testing.assert_array_equal(a["depth"], b["depth"])
        assert np.isnan(a["depth"][~a["mask"]]).all()
        assert a["direction"] == pytest.approx(scored["direction"])
        assert a["mask"].sum() > 1000


def test_render_own_frame_layout_and_lighting():
    views = qm3d.render(MONKEY, resolution=64, layout="cmdm18", lighting="headlight")["views"]
    assert len(views) == 18
    lit = qm3d.render(MONKEY, resolution=64, views=2, lighting="headlight")["views"][0]["rgb"]
    flat = qm3d.render(MONKEY, resolution=64, views=2)["views"][0]["rgb"]
    assert lit.astype(int).sum() < flat.astype(int).sum()  # shading only darkens


def test_mesh_against_cloud_arrays():
    mesh = qm3d.read_mesh(MONKEY)
    cloud = qm3d.sample(MONKEY, points=100000)
    res = qm3d.ibsm((mesh["positions"], mesh["colors"], mesh["faces"]),
                    (cloud["positions"], cloud["colors"]), resolution=256, views=4)
    assert 30 < res.score < 99.99
    assert res.to_dict()["splat_size_distorted"] > 0
    # The cloud is drawn as splats, the mesh as faces: both render.
    cloud_view = qm3d.render((cloud["positions"], cloud["colors"]), resolution=128, views=2)
    assert cloud_view["views"][0]["mask"].sum() > 1000


def test_bad_requests():
    with pytest.raises(ValueError):
        qm3d.ibsm(MONKEY, SIMPLIFIED, views=6, layout="cmdm18")
    with pytest.raises(ValueError):
        qm3d.ibsm(MONKEY, SIMPLIFIED, rotation=[1, 2])
    with pytest.raises(ValueError):
        qm3d.render(MONKEY, lighting="sun")
    with pytest.raises(ValueError):
        qm3d.render(MONKEY, frame=[0, 0, 0, -1])
    with pytest.raises(OSError):
        qm3d.render(os.path.join(SHARED, "no_such_file.ply"))
