"""SSIM and MS-SSIM of `qm3d ibsm`'s saved views (issue 27): each view's `ssim` equals the mean,
over the pixels both images cover, of scikit-image 0.19's structural_similarity map
(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=255, full=True), and
its `ms_ssim` equals Wang, Simoncelli and Bovik 2003's eq. 7 written here with numpy and the
pooling qm3d/render/image_quality.h documents, both within 1e-9.
"""

import json
import os
import subprocess

import numpy as np
import pytest

skimage_metrics = pytest.importorskip("skimage.metrics")
skimage_io = pytest.importorskip("skimage.io")
from scipy.ndimage import gaussian_filter  # noqa: E402  (skimage depends on scipy)

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.environ.get("QM3D_SOURCE_DIR", os.path.join(HERE, "..", ".."))
SHARED = os.environ.get("QM3D_SHARED_DATA_DIR", os.path.join(SOURCE, "..", "shared", "data"))
BINARY = os.environ.get("QM3D_BINARY", os.path.join(SOURCE, "build", "apps", "qm3d"))
REFERENCE = os.path.join(SHARED, "reference", "cmdm", "blob4_ref.ply")
DISTORTED = os.path.join(SHARED, "reference", "cmdm", "blob4_bothnoise.ply")

C1 = (0.01 * 255) ** 2
C2 = (0.03 * 255) ** 2
WEIGHTS = (0.0448, 0.2856, 0.3001, 0.2363, 0.1333)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    if not os.path.exists(BINARY):
        pytest.skip("qm3d tool not built: " + BINARY)
    views = tmp_path_factory.mktemp("views")
    out = subprocess.run([BINARY, "ibsm", REFERENCE, DISTORTED, "--resolution", "256",
                          "--views", "4", "--save-views", str(views), "--json", "--quiet"],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout), views


def luma_and_alpha(path):
    """ibsm.cpp's luma: float32 0.2126 r + 0.7152 g + 0.0722 b in that order, then float64."""
    rgba = skimage_io.imread(str(path))
    assert rgba.ndim == 3 and rgba.shape[2] == 4
    r, g, b = (rgba[..., c].astype(np.float32) for c in range(3))
    luma = np.float32(0.2126) * r + np.float32(0.7152) * g + np.float32(0.0722) * b
    assert luma.dtype == np.float32
    return luma.astype(np.float64), rgba[..., 3]


def view_pair(views, i):
    a, alpha_a = luma_and_alpha(views / ("view_%02d_reference.png" % i))
    b, alpha_b = luma_and_alpha(views / ("view_%02d_distorted.png" % i))
    return a, b, (alpha_a != 0) & (alpha_b != 0)


def local_terms(a, b):
    """Luminance and contrast-structure maps (Gaussian window, population statistics)."""
    f = lambda x: gaussian_filter(x, sigma=1.5, truncate=3.5, mode="reflect")
    ma, mb = f(a), f(b)
    va, vb, cov = f(a * a) - ma * ma, f(b * b) - mb * mb, f(a * b) - ma * mb
    lum = (2 * ma * mb + C1) / (ma * ma + mb * mb + C1)
    cs = (2 * cov + C2) / (va + vb + C2)
    return lum, cs


def halve(x):
    h, w = x.shape[0] // 2 * 2, x.shape[1] // 2 * 2
    x = x[:h, :w]
    return (x[0::2, 0::2] + x[0::2, 1::2] + x[1::2, 0::2] + x[1::2, 1::2]) / 4


def halve_mask(m):
    h, w = m.shape[0] // 2 * 2, m.shape[1] // 2 * 2
    m = m[:h, :w]
    return m[0::2, 0::2] & m[0::2, 1::2] & m[1::2, 0::2] & m[1::2, 1::2]


def ms_ssim(a, b, mask):
    """Eq. 7: l_M^beta_M * prod_j cs_j^beta_j, each term the mean over that scale's mask."""
    result = 1.0
    for j, beta in enumerate(WEIGHTS):
        lum, cs = local_terms(a, b)
        result *= max(cs[mask].mean(), 0.0) ** beta
        if j == len(WEIGHTS) - 1:
            return result * lum[mask].mean() ** beta
        a, b, mask = halve(a), halve(b), halve_mask(mask)


def test_ssim_equals_skimage(run):
    result, views = run
    assert len(result["views"]) == 4
    worst = 0.0
    for i, view in enumerate(result["views"]):
        a, b, mask = view_pair(views, i)
        assert mask.sum() == view["matched_pixels"]
        _, s_map = skimage_metrics.structural_similarity(
            a, b, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
            data_range=255, full=True)
        expected = s_map[mask].mean()
        worst = max(worst, abs(view["ssim"] - expected))
        assert view["ssim"] == pytest.approx(expected, abs=1e-9)
        assert 0.5 < view["ssim"] < 1  # noise lowers it, but the views still look alike
    print("max |ssim - skimage| =", worst)


def test_ms_ssim_equals_paper_formula(run):
    result, views = run
    worst = 0.0
    for i, view in enumerate(result["views"]):
        a, b, mask = view_pair(views, i)
        expected = ms_ssim(a, b, mask)
        worst = max(worst, abs(view["ms_ssim"] - expected))
        assert view["ms_ssim"] == pytest.approx(expected, abs=1e-9)
    print("max |ms_ssim - formula| =", worst)


def test_identical_views_score_one(run):
    _, views = run
    a, _, mask = view_pair(views, 0)
    assert ms_ssim(a, a, mask) == pytest.approx(1.0, abs=1e-12)
