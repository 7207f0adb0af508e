"""Issue 24, the readers from Python: number parsing whatever the locale, colour_scale=, and the
readers' warnings. Run by ctest (python_tests) with PYTHONPATH set to the build's python/ folder."""

import locale
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import qm3d

SOURCE = Path(os.environ.get("QM3D_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CLOUD = SOURCE / "data" / "clouds" / "sphere_2k_ref.ply"

ASCII_PCD = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
             "COUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
             "0.5 1.5 2.25 13132850\n-0.5 0.25 3.5 13132850\n")
ASCII_PLY = ("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
             "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
             "end_header\n0.5 1.5 2.25 200 100 50\n-0.5 0.25 3.5 200 100 50\n")
EXPECTED = np.array([[0.5, 1.5, 2.25], [-0.5, 0.25, 3.5]])


def comma_locale(tmp_path):
    """Sets LC_ALL to de_DE.UTF-8 (built with localedef into tmp_path when not installed);
    skips with the reason only when this machine cannot have it."""
    try:
        locale.setlocale(locale.LC_ALL, "de_DE.UTF-8")
    except locale.Error:
        if not shutil.which("localedef") or not Path("/usr/share/i18n/locales/de_DE").exists():
            pytest.skip("de_DE.UTF-8 is not installed and cannot be built (needs localedef and "
                        "/usr/share/i18n/locales from the Debian package 'locales')")
        subprocess.run(["localedef", "-i", "de_DE", "-f", "UTF-8",
                        str(tmp_path / "de_DE.UTF-8")], check=False, capture_output=True)
        os.environ["LOCPATH"] = str(tmp_path)
        locale.setlocale(locale.LC_ALL, "de_DE.UTF-8")  # an error here fails the test
    assert locale.localeconv()["decimal_point"] == ","


def test_a_comma_decimal_locale_changes_no_number_read(tmp_path):
    (tmp_path / "c.pcd").write_text(ASCII_PCD)
    (tmp_path / "c.ply").write_text(ASCII_PLY)
    try:
        comma_locale(tmp_path)
        for name in ("c.pcd", "c.ply"):
            cloud = qm3d.read_cloud(tmp_path / name)
            np.testing.assert_array_equal(cloud["positions"], EXPECTED, err_msg=name)
            np.testing.assert_array_equal(cloud["colors"][0], [200 / 255, 100 / 255, 50 / 255])
    finally:
        locale.setlocale(locale.LC_ALL, "C")
        os.environ.pop("LOCPATH", None)


def float_colour_cloud(path, odd=None):
    """The bundled 2000-point cloud with float 0..1 colours, one green replaced by `odd`."""
    c = qm3d.read_cloud(CLOUD)
    colors = [[repr(float(v)) for v in row] for row in c["colors"]]
    if odd is not None:
        colors[5][1] = odd
    lines = [f"{x!r} {y!r} {z!r} {' '.join(rgb)}" for (x, y, z), rgb in
             zip(c["positions"].tolist(), colors)]
    path.write_text("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                    "property float z\nproperty float red\nproperty float green\n"
                    "property float blue\nend_header\n" % len(lines) + "\n".join(lines) + "\n")
    return path


def test_colour_scale_keyword_and_the_warning(tmp_path):
    ref = float_colour_cloud(tmp_path / "ref.ply")
    odd = float_colour_cloud(tmp_path / "odd.ply", "1.0000001")
    read = qm3d.read_cloud(odd)
    assert len(read["warnings"]) == 1
    assert "1 of 6000 colour values above 1 (max 1.0000001192092896): read as 0..255" in \
        read["warnings"][0]
    automatic = qm3d.pcqm(ref, odd)
    assert any("read as 0..255 like the reference" in w for w in automatic.warnings)
    unit = qm3d.pcqm(ref, odd, colour_scale="unit")
    assert any("clamped to 1 (--colour-scale unit)" in w for w in unit.warnings)
    assert unit.score < 1e-3 < automatic.score
    assert qm3d.read_cloud(odd, colour_scale="unit")["colors"][5][1] == 1.0
    with pytest.raises(ValueError, match="colour_scale"):
        qm3d.pcqm(ref, odd, colour_scale="percent")
    with pytest.raises(ValueError, match="colour_scale"):
        qm3d.read_mesh(odd, colour_scale=255)
