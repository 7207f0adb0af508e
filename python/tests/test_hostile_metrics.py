"""Issue 37 (metric side) from Python: grid sampling that overflowed float32 killed the
interpreter (SIGSEGV), and one that ran out of memory aborted it; both are now exceptions."""

import os

import pytest

import qm3d

DATA = os.path.join(os.path.dirname(__file__), "..", "..", "data", "meshes")


def scaled(src, dst, scale):
    """A bundled COFF mesh with its coordinates multiplied by `scale`."""
    with open(src) as f:
        lines = f.read().split("\n")
    nv = int(lines[1].split()[0])
    for i in range(2, 2 + nv):
        p = lines[i].split()
        lines[i] = " ".join([repr(float(x) * scale) for x in p[:3]] + p[3:])
    with open(dst, "w") as f:
        f.write("\n".join(lines))
    return str(dst)


def test_huge_coordinates_raise_instead_of_killing_the_interpreter(tmp_path):
    ref = scaled(os.path.join(DATA, "blob3_ref.off"), tmp_path / "ref.off", 1e14)
    dist = scaled(os.path.join(DATA, "blob3_geonoise.off"), tmp_path / "dist.off", 1e14)
    with pytest.raises(qm3d.NumericError, match="overflows float32"):
        qm3d.psnr(ref, dist)


def test_a_grid_too_fine_is_a_memory_error_with_the_estimate():
    ref = os.path.join(DATA, "blob3_ref.off")
    dist = os.path.join(DATA, "blob3_geonoise.off")
    with pytest.raises(MemoryError, match="grid size 30000 gives about"):
        qm3d.psnr(ref, dist, grid_size=30000)
