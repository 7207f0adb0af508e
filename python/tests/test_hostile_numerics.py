"""Numerically hostile calls from Python (issue 24): none may kill the interpreter or return a
non-finite score. Run by ctest (python_tests) with PYTHONPATH set to the build's python/ folder."""

import math

import numpy as np
import pytest

import qm3d

COLOURS = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])


def tetrahedron(scale=1.0):
    positions = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]) * scale
    colours = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0.5, 0.5, 0.5]])
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return positions, colours, faces


def test_a_face_repeated_tens_of_thousands_of_times_does_not_kill_the_interpreter():
    # 40,000 copies: CGAL's k-d tree recursed once per copy and overflowed the stack.
    faces = np.tile(np.array([[0, 1, 2]]), (40000, 1))
    mesh = (np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), COLOURS, faces)
    assert qm3d.msdm2(mesh, mesh).score == 0.0
    assert qm3d.cmdm(mesh, mesh).score == 0.0


@pytest.mark.parametrize("threads", [65536, 10**6])
def test_absurd_thread_counts_are_a_value_error(threads):
    mesh = tetrahedron()
    with pytest.raises(ValueError, match="threads: .* is more than the"):
        qm3d.cmdm(mesh, mesh, threads=threads)


@pytest.mark.parametrize("scale", [1e100, 1e300, 1e-100, 1e-300])
def test_coordinates_whose_squares_overflow_or_underflow_are_a_numeric_error(scale):
    mesh = tetrahedron(scale)
    for metric in (qm3d.cmdm, qm3d.msdm2, qm3d.pcqm):
        with pytest.raises(qm3d.NumericError, match="squared distances would"):
            metric(mesh, mesh)


def test_a_radius_out_of_range_is_a_value_error():
    mesh = tetrahedron()
    with pytest.raises(ValueError, match="radius"):
        qm3d.pcqm(mesh, mesh, radius=1e-300)


def test_nan_weights_are_a_value_error():
    mesh = tetrahedron()
    with pytest.raises(ValueError, match="weights"):
        qm3d.cmdm(mesh, mesh, weights=[math.nan] + [0.0] * 7)
