"""qm3d.image_quality and qm3d.icid (issue 40): the iCID reference table's synthetic rows (every
option) and one stimulus's 18-view mean within 1e-10 relative (tests/icid_reference.h's rule: an
absolute floor of 1e-13 for the values the reference gets from rounding alone), identical images,
RGBA arrays, the per-pixel map, thread counts, and bad arrays refused.
"""

import csv
import os

import numpy as np
import open3d as o3d
import pytest

import qm3d
from test_psnr import SHARED

ICID = os.path.join(SHARED, "reference", "icid")
OPTIONS = {"default": {}, "Intent=hue-preserving": {"intent": "hue-preserving"},
           "Intent=chromatic": {"intent": "chromatic"}, "IAM=NONE": {"iam": False},
           "Omit_Maps67=true": {"omit_maps67": True}, "Downsampling=false": {"downsampling": False}}
NAMES = ["icid"] + [f"icid_m{k}" for k in range(1, 8)]


def rows():
    with open(os.path.join(ICID, "icid_reference.csv"), newline="") as f:
        return list(csv.reader(f, delimiter=";"))[1:]


def image(relative):
    # open3d's own PNG reader: independent of qm3d's
    return np.asarray(o3d.io.read_image(os.path.join(ICID, relative)))


def as_octave_read(pixels):
    # The table's Octave run read an image whose red channel is all 0 / 255 as a logical array,
    # which iCID.m and colorspace.m turn into 0 / (1/255) (tests/icid_reference.h,
    # read_as_octave): synth_colour_bars. qm3d reads images as MATLAB does.
    if np.isin(pixels[..., 0], (0, 255)).all():
        return (pixels > 0).astype(np.uint8)
    return pixels


def close(got, want):
    return abs(got - want) <= 1e-10 * abs(want) + 1e-13


@pytest.mark.parametrize("row", [r for r in rows() if r[0].startswith("synth")],
                         ids=lambda r: f"{r[0]}-{r[3]}")
def test_synthetic_rows(row):
    got = qm3d.image_quality(as_octave_read(image(row[1])), as_octave_read(image(row[2])),
                             **OPTIONS[row[3]])
    for name, text in zip(NAMES, row[4:]):
        assert close(got[name], float(text)), (name, got[name], text)


def test_18_view_mean_of_a_stimulus():
    views = [r for r in rows() if r[0].startswith("blob4_geonoise:view")]
    assert len(views) == 18
    mean = dict.fromkeys(NAMES, 0.0)
    for r in views:
        got = qm3d.image_quality(image(r[1]), image(r[2]))
        for name in NAMES:
            mean[name] += got[name] / 18
    want = next(r for r in rows() if r[0] == "blob4_geonoise:mean18")
    for name, text in zip(NAMES, want[4:]):
        assert close(mean[name], float(text)), (name, mean[name], text)


def test_identical_rgba_threads_and_map():
    a = image("views/blob4_geonoise/view_03_reference.png")
    b = image("views/blob4_geonoise/view_03_distorted.png")
    assert a.shape[2] in (3, 4)
    alpha = np.concatenate([a[:, :, :3], np.full(a.shape[:2] + (1,), 7, np.uint8)], axis=2)
    same = qm3d.image_quality(a, a)
    assert abs(same["icid"]) <= 1e-13 and same["psnr"] == float("inf")
    one = qm3d.image_quality(alpha, b, threads=1)
    two, pixel_map = qm3d.image_quality(a[:, :, :3], b, threads=2, return_map=True)
    assert one == two  # alpha dropped; the same bits on 1 and 2 threads
    assert pixel_map.shape == (246, 246)
    assert pixel_map.mean() == pytest.approx(two["icid"], abs=1e-12)


def test_bad_arrays_refused():
    a = image("synth/synth_noise_a.png")
    with pytest.raises(ValueError, match="uint8"):
        qm3d.image_quality(a.astype(float), a)
    with pytest.raises(ValueError, match="shape"):
        qm3d.image_quality(a[:, :, 0], a[:, :, 0])
    with pytest.raises(ValueError, match="same size"):
        qm3d.image_quality(a, a[:64])
    with pytest.raises(ValueError, match="intent"):
        qm3d.image_quality(a, a, intent="vivid")


def test_icid_metric_function_exists():
    spec = next(m for m in qm3d.metrics() if m["name"] == "icid")
    assert spec["value_names"] == NAMES
    assert not spec["higher_is_better"]


def test_icid_metric_on_meshes():
    data = os.path.join(os.path.dirname(__file__), "..", "..", "data", "meshes")
    ref, dist = (os.path.join(data, f"blob3_{n}.off") for n in ("ref", "bothnoise"))
    one = qm3d.icid(ref, dist, resolution=64, threads=1)
    two = qm3d.icid(ref, dist, resolution=64, threads=2)
    assert one.score == two.score > 0
    views = one.to_dict()["views"]
    assert len(views) == 18
    assert one.score == pytest.approx(sum(v["icid"] for v in views) / 18, rel=1e-14)
    assert qm3d.icid(ref, ref, resolution=64).score == pytest.approx(0, abs=1e-13)
