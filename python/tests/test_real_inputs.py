"""Issue 39 from Python: texture maps given per input (ref_texture= / dist_texture=, sample's
texture=), PLY meshes with `comment TextureFile`, BMP maps, the warning for texture coordinates
without a usable texture, mmetric's textured IBSM frame, PCD clouds with NaN points, and
psnr(conventions="mmetric") on clouds against mm compare --mode pcc."""

import csv
import math
import os

import numpy as np
import pytest

import qm3d
from test_psnr import COLUMNS, SHARED, expect

TEXTURED = os.path.join(SHARED, "reference", "mpeg", "textured")
CLOUDS_PCC = os.path.join(SHARED, "reference", "mpeg", "clouds_pcc", "mm_pcc_clouds_reference.csv")
SIDE = 10


def _z(i, j, noise):
    return 0.8 * math.sin(0.6 * i) * math.cos(0.5 * j) + noise * math.sin(7.0 * i + 3.0 * j)


def _uv(i, j):
    return (i + 0.25) / (SIDE - 0.5), 1 - (j + 0.4) / (SIDE - 0.2)


def _faces():
    for j in range(SIDE - 1):
        for i in range(SIDE - 1):
            a = j * SIDE + i
            yield a, a + 1, a + SIDE + 1
            yield a, a + SIDE + 1, a + SIDE


def write_obj(path, head, noise):
    lines = [head]
    for j in range(SIDE):
        for i in range(SIDE):
            u, v = _uv(i, j)
            lines.append(f"v {i} {j} {_z(i, j, noise)!r}\nvt {u!r} {v!r}")
    lines += ["f " + " ".join(f"{k + 1}/{k + 1}" for k in f) for f in _faces()]
    path.write_text("\n".join(lines) + "\n")
    return path


def write_ply(path, comments, noise):
    faces = list(_faces())
    lines = ["ply", "format ascii 1.0", *comments, f"element vertex {SIDE * SIDE}",
             "property double x", "property double y", "property double z", "property double s",
             "property double t", f"element face {len(faces)}",
             "property list uchar int vertex_indices", "end_header"]
    for j in range(SIDE):
        for i in range(SIDE):
            u, v = _uv(i, j)
            lines.append(f"{i} {j} {_z(i, j, noise)!r} {u!r} {v!r}")
    lines += ["3 " + " ".join(str(k) for k in f) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def write_maps(tmp_path):
    """The same random 8 x 8 map as PNG and as 24-bit BMP (both written here with zlib and
    struct), and an MTL naming each."""
    import struct
    import zlib
    rng = np.random.default_rng(5)
    rgb = rng.integers(0, 256, size=(8, 8, 3), dtype=np.uint8)
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(8))
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 8, 8, 8, 2, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
    (tmp_path / "map.png").write_bytes(png)
    rows = b"".join(rgb[y][:, ::-1].tobytes() for y in range(7, -1, -1))  # BGR, bottom-up
    header = (b"BM" + struct.pack("<IHHI", 54 + len(rows), 0, 0, 54) +
              struct.pack("<IiiHHIIiiII", 40, 8, 8, 1, 24, 0, len(rows), 2835, 2835, 0, 0))
    (tmp_path / "map.bmp").write_bytes(header + rows)
    (tmp_path / "png.mtl").write_text("newmtl m\nmap_Kd map.png\n")
    (tmp_path / "bmp.mtl").write_text("newmtl m\nmap_Kd map.bmp\n")


def test_ply_texture_file_bmp_map_and_given_maps_score_as_the_obj_png(tmp_path):
    write_maps(tmp_path)
    ref = write_obj(tmp_path / "ref.obj", "mtllib png.mtl\nusemtl m", 0)
    png = write_obj(tmp_path / "png.obj", "mtllib png.mtl\nusemtl m", 0.05)
    bmp = write_obj(tmp_path / "bmp.obj", "mtllib bmp.mtl\nusemtl m", 0.05)
    ply = write_ply(tmp_path / "dist.ply", ["comment TextureFile map.png"], 0.05)
    bare = write_obj(tmp_path / "bare.obj", "", 0.05)
    want = qm3d.psnr(ref, png, grid_size=48, bilinear=True).features
    assert "c0_mse" in want  # textured: colour values
    assert qm3d.psnr(ref, bmp, grid_size=48, bilinear=True).features == want
    assert qm3d.psnr(ref, ply, grid_size=48, bilinear=True).features == want
    given = qm3d.psnr(ref, bare, grid_size=48, bilinear=True, dist_texture=tmp_path / "map.bmp")
    assert given.features == want
    ibsm = dict(resolution=200, views=4, no_ssim=True)
    assert (qm3d.ibsm(ref, bare, dist_texture=str(tmp_path / "map.png"), **ibsm).features ==
            qm3d.ibsm(ref, png, **ibsm).features)
    # Without the map: one warning naming the mesh and the keyword; geometry values only.
    r = qm3d.psnr(ref, bare, grid_size=48)
    lines = [w for w in r.warnings if "read without its texture" in w]
    assert len(lines) == 1 and "bare.obj" in lines[0] and "dist_texture=" in lines[0], r.warnings
    assert "c0_mse" not in r.features
    # sample(texture=) as the textured file.
    a = qm3d.sample(ply, mode="grid", grid_size=32)
    b = qm3d.sample(bare, mode="grid", grid_size=32, texture=tmp_path / "map.png")
    np.testing.assert_array_equal(a["colors"], b["colors"])


def test_a_bad_given_map_is_one_error_naming_it(tmp_path):
    write_maps(tmp_path)
    ref = write_obj(tmp_path / "ref.obj", "mtllib png.mtl\nusemtl m", 0)
    (tmp_path / "bad.png").write_text("not an image")
    with pytest.raises(qm3d.FormatError, match="bad.png: cannot decode the texture image"):
        qm3d.psnr(ref, ref, grid_size=16, dist_texture=tmp_path / "bad.png")
    with pytest.raises(qm3d.InputError, match="absent.png"):
        qm3d.psnr(ref, ref, grid_size=16, ref_texture=tmp_path / "absent.png")


def test_mmetric_textured_frame_with_its_maps():
    with open(os.path.join(TEXTURED, "mm_ibsm_textured_reference.csv"), newline="") as f:
        row = next(r for r in csv.DictReader(f, delimiter=";") if r["case"] == "bb3_qp16")
    png = os.path.join(TEXTURED, "basketball_player_00000003.png")
    res = qm3d.ibsm(os.path.join(TEXTURED, row["mesh_a"]), os.path.join(TEXTURED, row["mesh_b"]),
                    ref_texture=png, dist_texture=png, no_ssim=True, threads=2)
    features = res.directions["dist_to_ref"].features
    checked = 0
    for column, text in row.items():
        name = "unmatched_pixel_percentage" if column == "UnmatchedPixelPercentage" else column.lower()
        if name in features:
            assert features[name] == pytest.approx(float(text), rel=1e-8), column
            checked += 1
    assert checked == 19


def _pcd(path, points, width, height):
    head = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
            f"COUNT 1 1 1 1\nWIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\n"
            f"POINTS {width * height}\nDATA ascii\n")
    path.write_text(head + "".join(f"{x} {y} {z} {c}\n" for x, y, z, c in points))
    return path


def test_pcd_nan_points_are_dropped_with_one_warning(tmp_path):
    pts, clean, other = [], [], []
    for j in range(20):
        for i in range(30):
            p = (0.1 * i, 0.1 * j, round(0.3 * math.sin(0.3 * i + 0.2 * j), 6),
                 (6 * i << 16) | (9 * j << 8) | 77)
            nan = (i * 7 + j * 3) % 11 == 0
            pts.append(("nan", "nan", "nan", p[3]) if nan else p)
            if not nan:
                clean.append(p)
            other.append((p[0], p[1], round(p[2] + 0.01 * math.cos(5 * i), 6), p[3] ^ 0x0f0f0f))
    with_nan = _pcd(tmp_path / "nan.pcd", pts, 30, 20)
    dense = _pcd(tmp_path / "clean.pcd", clean, len(clean), 1)
    dist = _pcd(tmp_path / "other.pcd", other, 30, 20)
    cloud = qm3d.read_cloud(with_nan)
    assert len(cloud["positions"]) == len(clean)
    assert cloud["warnings"] == [f"{with_nan}: {600 - len(clean)} of 600 points have a NaN or "
                                 "infinite coordinate (invalid measurements of an organised "
                                 "cloud): dropped, as pcl::removeNaNFromPointCloud does"]
    for name in ("pcqm", "psnr", "dlab"):
        assert (qm3d.metric(name, with_nan, dist).features ==
                qm3d.metric(name, dense, dist).features), name
    all_nan = _pcd(tmp_path / "all.pcd", [("nan", "nan", "nan", 1)] * 2, 2, 1)
    with pytest.raises(qm3d.FormatError, match="all.pcd: all 2 points have a NaN"):
        qm3d.pcqm(all_nan, dist)


def _clouds_pcc_cases():
    with open(CLOUDS_PCC, newline="") as f:
        return list(csv.DictReader(f, delimiter=";"))


@pytest.mark.parametrize("case", _clouds_pcc_cases(), ids=lambda c: c["case"])
def test_psnr_conventions_mmetric_on_clouds(case):
    args = case["args"].split()
    kw = {"conventions": "mmetric"}
    for i, a in enumerate(args):
        value = args[i + 1] if i + 1 < len(args) else ""
        if a == "--resolution":
            kw["peak"] = float(value)
        elif a == "--normalCalcModificationEnable=false":
            kw["d2_normals"] = "transferred"
        elif a == "--color=false":
            kw["no_color"] = True
        elif a == "--dropDuplicates":
            kw["drop_duplicates"] = int(value)
        elif a == "--neighborsProc":
            kw["neighbours"] = int(value)
        elif a == "--singlePass":
            kw["direction"] = "ref-to-dist"
    r = qm3d.psnr(os.path.join(SHARED, case["a"]), os.path.join(SHARED, case["b"]), **kw)
    for column in COLUMNS:
        name = column.replace("haus", "hausdorff")
        expect(case, "AB_" + column, r.ref_to_dist.features.get(name))
        if "direction" not in kw:
            expect(case, "BA_" + column, r.dist_to_ref.features.get(name))
            expect(case, "sym_" + column, r.features.get(name))
    assert r.details["peak"] == pytest.approx(float(case["peak"]), rel=1e-8)
