"""What the Python bindings do under interruption, in threads and with bad arguments (issue 24):
Ctrl-C interrupts a long call, other Python threads run while a metric computes (the GIL is
released), and non-finite or absurd arguments are ValueErrors naming the argument. No test here
measures elapsed time: each checks an order of events that a held GIL or an uninterruptible
call cannot produce."""

import os
import signal
import threading

import numpy as np
import pytest

import qm3d
from qm3d import _qm3d


def sphere_pair(points):
    """A coloured unit sphere and the same points with their red halved (a pure-colour change)."""
    rng = np.random.default_rng(7)
    p = rng.normal(size=(points, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    c = rng.integers(0, 256, size=(points, 3), dtype=np.uint8)
    d = c.copy()
    d[:, 0] //= 2
    return (p, c), (p, d)


# PCQM on this pair reports its stages (search trees, curvatures and correspondences, features,
# done); each of the middle stages is a large share of the call on one thread.
REF, DIST = sphere_pair(200_000)


def test_ctrl_c_interrupts_a_metric_call_before_it_finishes():
    # The progress callback is a builtin (dict.__setitem__), so no Python bytecode runs inside
    # the call: only the bindings themselves can notice the signal before the call returns.
    reports = {}

    def press_ctrl_c_once_the_metric_has_started():
        while not reports:
            pass
        os.kill(os.getpid(), signal.SIGINT)

    presser = threading.Thread(target=press_ctrl_c_once_the_metric_has_started)
    presser.start()
    with pytest.raises(KeyboardInterrupt):
        qm3d.pcqm(REF, DIST, threads=1, progress=reports.__setitem__)
    presser.join()
    # The call was interrupted, not completed and then interrupted: the metric stops at its next
    # stage boundary and never reports "done", even once its worker has stopped.
    _qm3d.wait_for_interrupted_calls()
    assert "done" not in reports, reports
    # The package is still usable afterwards.
    assert qm3d.pcqm(REF, REF, threads=1).score < 1e-12


def test_another_python_thread_runs_while_a_metric_computes():
    # The metric's progress reports go to a builtin (dict.__setitem__: no bytecode, so no GIL
    # hand-over inside the callback). The main thread records how many reports it sees while it
    # spins. Had the call held the GIL, the main thread could run only before the first report
    # and after the last one, never in between.
    reports = {}
    results = []
    worker = threading.Thread(target=lambda: results.append(
        qm3d.pcqm(REF, DIST, threads=1, progress=reports.__setitem__)))
    seen = set()
    worker.start()
    while worker.is_alive():
        seen.add(len(reports))  # pure Python: needs the GIL
    worker.join()
    assert results, "the metric call failed"
    assert "done" in reports and len(reports) >= 3, reports
    assert seen & set(range(1, len(reports))), (seen, reports)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf")])
def test_non_finite_options_are_value_errors(value):
    with pytest.raises(ValueError, match="radius"):
        qm3d.pcqm(REF, DIST, radius=value)
    with pytest.raises(ValueError, match="weights"):
        qm3d.pcqm(REF, DIST, weights=[value] + [0.1] * 7)


@pytest.mark.parametrize("threads", [-1, 2**40, 1.5, "2"])
def test_bad_thread_counts_are_value_errors(threads):
    with pytest.raises(ValueError, match="threads"):
        qm3d.pcqm(REF, DIST, threads=threads)
