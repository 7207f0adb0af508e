"""qm3d.dlab (D_LAB, the colour baseline of the CMDM report, issue 26 item 4) against a numpy
computation on colour-only distortions (identical geometry: each element's correspondence is
the element of the same index): the colours read from the files with numpy, converted to
LAB2000HL with the shared tables as common/src/color.cpp converts them, the per-element
Euclidean distance and its mean, within 1e-9 relative.
"""

import os

import numpy as np
import pytest

import qm3d

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
DATA = os.path.join(ROOT, "data")
CLOUD_REF = os.path.join(DATA, "clouds", "sphere_2k_ref.ply")
CLOUD_DIST = os.path.join(DATA, "clouds", "sphere_2k_cnoise10.ply")
MESH_REF = os.path.join(DATA, "meshes", "blob3_ref.off")
MESH_DIST = os.path.join(DATA, "meshes", "blob3_colnoise.off")
TABLES = os.environ.get("QM3D_DATA_DIR") or os.path.join(ROOT, "..", "shared", "data", "lab2000hl")

RTOL = 1e-9


# ---- the files, read with numpy -------------------------------------------------------------

def read_ascii_ply(path):
    """Positions and 8-bit colours of an ASCII PLY cloud (x y z red green blue per vertex)."""
    with open(path) as f:
        lines = f.read().splitlines()
    end = lines.index("end_header")
    count = int(next(l.split()[2] for l in lines[:end] if l.startswith("element vertex")))
    rows = np.array([l.split() for l in lines[end + 1:end + 1 + count]], dtype=float)
    return rows[:, :3], rows[:, 3:6]


def read_coff(path):
    """Positions, 8-bit colours and triangles of a COFF mesh."""
    with open(path) as f:
        lines = [l for l in f.read().splitlines() if l.strip() and not l.startswith("#")]
    assert lines[0] == "COFF"
    nv, nf = (int(x) for x in lines[1].split()[:2])
    rows = np.array([l.split()[:6] for l in lines[2:2 + nv]], dtype=float)
    faces = np.array([l.split()[1:4] for l in lines[2 + nv:2 + nv + nf]], dtype=np.int64)
    return rows[:, :3], rows[:, 3:6], faces


# ---- sRGB -> CIELab -> LAB2000HL in numpy (common/src/color.cpp) ------------------------------

SRGB_TO_XYZ = np.array([[0.412396, 0.357583, 0.180493],
                        [0.212586, 0.71517, 0.0722005],
                        [0.0192972, 0.119184, 0.950497]])
WHITE = np.array([0.950456, 1.0, 1.088754])


def srgb_to_cielab(rgb01):
    c = np.where(rgb01 > 0.0404482362771076, ((rgb01 + 0.055) / 1.055) ** 2.4, rgb01 / 12.92)
    xyz = c @ SRGB_TO_XYZ.T / WHITE
    f = np.where(xyz > 0.008856, np.cbrt(xyz), (841.0 / 108.0) * xyz + 4.0 / 29.0)
    return np.stack([116.0 * f[:, 1] - 16.0, 500.0 * (f[:, 0] - f[:, 1]),
                     200.0 * (f[:, 1] - f[:, 2])], axis=1)


class Tables:
    def __init__(self, folder):
        load = lambda name: np.loadtxt(os.path.join(folder, name))
        self.lightness = load("L_data.txt")
        a_coord = load("RegularGridInit_0_0_1.txt").astype(int) + 128
        b_coord = load("RegularGridInit_0_0_2.txt").astype(int) + 128
        self.a_hl = np.zeros((257, 257))
        self.b_hl = np.zeros((257, 257))
        self.a_hl[a_coord, b_coord] = load("RegularGrid_0_0_1.txt")
        self.b_hl[a_coord, b_coord] = load("RegularGrid_0_0_2.txt")

    def light(self, l_star):
        n = len(self.lightness)
        grid = np.arange(n) * 0.001
        pos = np.searchsorted(grid, l_star, side="right")  # the first grid value above L*
        inside = (l_star >= 0) & (pos < n)
        p = np.clip(pos, 1, n - 1)
        x0, x1 = grid[p - 1], grid[p]
        y0, y1 = self.lightness[p - 1], self.lightness[p]
        value = y0 + ((l_star - x0) / (x1 - x0)) * (y1 - y0)
        return np.where(inside, value, np.where(l_star < 0, self.lightness[0], self.lightness[-1]))

    def bilinear(self, grid, a, b):
        x0 = np.clip(np.floor(a), -128, 127).astype(int)
        y0 = np.clip(np.floor(b), -128, 127).astype(int)
        x1, y1 = x0 + 1, y0 + 1
        at = lambda x, y: grid[x + 128, y + 128]
        x1x, y1y, xx0, yy0 = x1 - a, y1 - b, a - x0, b - y0
        return 1.0 / ((x1 - x0) * (y1 - y0)) * (at(x0, y0) * x1x * y1y + at(x1, y0) * xx0 * y1y +
                                                at(x0, y1) * x1x * yy0 + at(x1, y1) * xx0 * yy0)

    def from_srgb(self, rgb01):
        lab = srgb_to_cielab(rgb01)
        return np.stack([self.light(lab[:, 0]), self.bilinear(self.a_hl, lab[:, 1], lab[:, 2]),
                         self.bilinear(self.b_hl, lab[:, 1], lab[:, 2])], axis=1)


@pytest.fixture(scope="module")
def tables():
    return Tables(TABLES)


def unit_colours(rgb8, mesh):
    """8-bit colours as the readers give them: k / 255, rounded to float32 for a mesh (the mesh
    reader stores colours at float precision, as MEPP2 does)."""
    c = rgb8 / 255.0
    return c.astype(np.float32).astype(np.float64) if mesh else c


def numpy_dlab(tables, ref_rgb, dist_rgb):
    """Per-element D_LAB on identical geometry (element i matches element i) and its mean."""
    per_element = np.linalg.norm(tables.from_srgb(ref_rgb) - tables.from_srgb(dist_rgb), axis=1)
    return per_element, per_element.mean()


# ---- the tests ------------------------------------------------------------------------------

def test_numpy_conversion_is_the_libraries(tables):
    # Pure colours and greys, where LAB2000HL's tables are far from linear: a check of the numpy
    # conversion itself, through D_LAB of one-point clouds against black.
    rgb = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 128, 128], [255, 255, 255],
                    [3, 7, 250]], dtype=float)
    black = np.zeros((1, 3))
    for c in rgb:
        point = np.zeros((1, 3))
        r = qm3d.dlab((point, c[None].astype(np.uint8)), (point, black.astype(np.uint8)))
        expected = np.linalg.norm(tables.from_srgb(c[None] / 255.0) - tables.from_srgb(black))
        assert r.score == pytest.approx(expected, rel=1e-12, abs=0), c


@pytest.mark.parametrize("ref, dist", [(CLOUD_REF, CLOUD_DIST), (MESH_REF, MESH_DIST)])
def test_colour_only_distortion_equals_numpy(tables, ref, dist):
    mesh = ref.endswith(".off")
    read = read_coff if mesh else read_ascii_ply
    ref_data, dist_data = read(ref), read(dist)
    np.testing.assert_array_equal(ref_data[0], dist_data[0])  # identical geometry
    per_element, mean = numpy_dlab(tables, unit_colours(ref_data[1], mesh),
                                   unit_colours(dist_data[1], mesh))
    assert mean > 1  # a visible colour distortion
    r = qm3d.dlab(ref, dist, per_element=True)
    assert r.score == pytest.approx(mean, rel=RTOL, abs=0)
    for direction in ("ref_to_dist", "dist_to_ref"):
        d = getattr(r, direction)
        assert d.score == pytest.approx(mean, rel=RTOL, abs=0), direction
        np.testing.assert_allclose(d.per_element, per_element, rtol=RTOL, atol=0)
    assert r.features["delta_e_mean"] == r.score
    assert r.features["delta_e_max"] == pytest.approx(per_element.max(), rel=RTOL, abs=0)


def test_metric_is_registered_with_its_orientation():
    spec = next(s for s in qm3d.metrics() if s["name"] == "dlab")
    assert spec["higher_is_better"] is False
    assert spec["applies_to"] == "both"
    assert spec["default_direction"] == "symmetric"
    assert spec["options"] == []


def test_identical_inputs_score_exactly_zero():
    for path in (CLOUD_REF, MESH_REF):
        r = qm3d.dlab(path, path, per_element=True)
        assert r.score == 0.0
        assert not r.ref_to_dist.per_element.any()


def test_symmetric_by_construction():
    a, b = MESH_REF, os.path.join(DATA, "meshes", "blob3_bothnoise.off")
    ab, ba = qm3d.dlab(a, b), qm3d.dlab(b, a)
    assert ab.score == ba.score
    assert ab.ref_to_dist.score == ba.dist_to_ref.score


def test_mesh_arrays_are_matched_on_the_surface_like_the_files():
    # Arrays with faces are read as meshes (CMDM's projection), as the files are.
    ref = read_coff(MESH_REF)
    dist = read_coff(os.path.join(DATA, "meshes", "blob3_bothnoise.off"))
    from_arrays = qm3d.dlab((ref[0], ref[1].astype(np.uint8), ref[2]),
                            (dist[0], dist[1].astype(np.uint8), dist[2]))
    from_files = qm3d.dlab(MESH_REF, os.path.join(DATA, "meshes", "blob3_bothnoise.off"))
    assert from_arrays.score == pytest.approx(from_files.score, rel=1e-12, abs=0)
    assert from_files.to_dict()["correspondence"].startswith("closest point")
    as_clouds = qm3d.dlab((ref[0], ref[1].astype(np.uint8)), (dist[0], dist[1].astype(np.uint8)))
    assert as_clouds.to_dict()["correspondence"].startswith("nearest point")


def test_a_cloud_without_colours_is_refused_naming_it(tmp_path):
    grey = tmp_path / "grey.ply"
    grey.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n")
    with pytest.raises(qm3d.FormatError, match="grey.ply: no vertex colours"):
        qm3d.dlab(CLOUD_REF, str(grey))
