"""Issue 44 item 2: every warning of a result is also raised as a qm3d.Qm3dWarning."""
import warnings

import numpy as np
import pytest

import qm3d


def _cloud_with_duplicates():
    rng = np.random.default_rng(4)
    p = rng.random((400, 3)) * 100  # pointssim's default radii need tens of units
    p[1] = p[0]  # a duplicate point: pointssim fuses it and warns
    c = rng.random((400, 3))
    return p, c


def test_qm3dwarning_is_an_exported_userwarning():
    assert "Qm3dWarning" in qm3d.__all__
    assert issubclass(qm3d.Qm3dWarning, UserWarning)


def test_result_warnings_are_raised_through_the_warnings_module():
    ref = _cloud_with_duplicates()
    with pytest.warns(qm3d.Qm3dWarning) as caught:
        r = qm3d.pointssim(ref, ref)
    assert r.warnings, "the duplicate point is warned of"
    raised = [str(w.message) for w in caught if issubclass(w.category, qm3d.Qm3dWarning)]
    assert raised == r.warnings
    assert all(len(line) <= 160 for line in raised)


def test_no_warning_no_qm3dwarning():
    rng = np.random.default_rng(5)
    p = rng.random((300, 3))
    ref, dist = (p, rng.random((300, 3))), (p, rng.random((300, 3)))
    with warnings.catch_warnings():
        warnings.simplefilter("error", qm3d.Qm3dWarning)
        r = qm3d.dlab(ref, dist)
    assert r.warnings == []
