"""Hostile counts and files through the Python package (issue 24): the library's checks reach
Python too (a bootstrap count that would never end, devices and pipes as inputs)."""

import os
import subprocess
from pathlib import Path

import pytest

import qm3d

SOURCE = Path(os.environ.get("QM3D_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CLOUD = SOURCE / "data" / "clouds" / "sphere_2k_ref.ply"
SCORES = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
MOS = [1.0, 2.5, 2.0, 4.0, 4.5, 5.0]


def test_a_huge_bootstrap_count_is_refused_not_run():
    with pytest.raises(ValueError, match="bootstrap replicates must be at most 100000"):
        qm3d.evaluate(SCORES, MOS, bootstrap=2**40)


def test_a_negative_bootstrap_count_is_refused():
    with pytest.raises((ValueError, TypeError, OverflowError)):
        qm3d.evaluate(SCORES, MOS, bootstrap=-1)


def test_a_device_is_refused_with_its_kind():
    with pytest.raises(Exception, match=r"/dev/zero: not a regular file \(character device\)"):
        qm3d.read_cloud("/dev/zero")


def test_a_fifo_is_read_like_the_file(tmp_path):
    fifo = tmp_path / "cloud.ply"
    os.mkfifo(fifo)
    # Another process writes (a Python thread would need the GIL that the read holds).
    writer = subprocess.Popen(["sh", "-c", 'cat "$0" > "$1"', str(CLOUD), str(fifo)])
    piped = qm3d.read_cloud(str(fifo))
    assert writer.wait(timeout=60) == 0
    direct = qm3d.read_cloud(str(CLOUD))
    assert (piped["positions"] == direct["positions"]).all()
    assert (piped["colors"] == direct["colors"]).all()
