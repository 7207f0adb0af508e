"""qm3d.dask.score_pairs on a real LocalCluster of 2 worker processes: batch's rows and scores,
failures as rows, and every pair exactly once when a worker dies mid-run."""

import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

pd = pytest.importorskip("pandas")
distributed = pytest.importorskip("distributed")

import qm3d.dask  # noqa: E402

SOURCE = Path(os.environ.get("QM3D_SOURCE_DIR", Path(__file__).resolve().parents[2]))
DATA = SOURCE / "data"
BINARY = os.environ.get("QM3D_BINARY")

if os.environ.get("QM3D_SANITIZED") == "1":
    pytest.skip("worker processes do not inherit the sanitizer preload reliably",
                allow_module_level=True)

MESH_PAIRS = [(DATA / "meshes" / "blob3_ref.off", DATA / "meshes" / f"blob3_{d}.off")
              for d in ("geonoise", "colnoise", "bothnoise")]
CLOUD_PAIRS = [(DATA / "clouds" / "sphere_2k_ref.ply", DATA / "clouds" / f"sphere_2k_{d}.ply")
               for d in ("cnoise10", "gnoise0.005", "down0.5")]


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def batch_table(tmp_path, rows):
    if not BINARY:
        pytest.skip("QM3D_BINARY not set (run through ctest)")
    listing = tmp_path / "list.csv"
    listing.write_text("reference,distorted,metric\n" +
                       "".join(f"{r},{d},{m}\n" for r, d, m in rows))
    out = tmp_path / "out.csv"
    subprocess.run([BINARY, "batch", str(listing), "-o", str(out), "--quiet"], check=False)
    # round_trip: pandas' default float parser is not exact in the last digit.
    return pd.read_csv(out, keep_default_na=False, na_values=[""], float_precision="round_trip")


def test_same_rows_and_scores_as_batch(client, tmp_path):
    rows = [(r, d, "auto") for r, d in MESH_PAIRS + CLOUD_PAIRS] + [(*MESH_PAIRS[0], "compare")]
    expected = batch_table(tmp_path, rows)
    table = qm3d.dask.score_pairs(rows, client=client, points=3000)
    # batch's last column, settings, records its command line's options (dask has its own).
    assert list(table.columns) == [c for c in expected.columns if c != "settings"]
    assert list(table["metric"]) == list(expected["metric"])
    assert list(table["reference"]) == list(expected["reference"])
    assert (table["status"] == "ok").all()
    # pcqm_sampled used --points 3000 here and the default in batch: compare the others.
    same = table["metric"] != "pcqm_sampled"
    for column in ["score", "dist_to_ref_score", "ref_to_dist_score", "ref_to_dist_f4"]:
        a, b = table.loc[same, column].to_numpy(), expected.loc[same, column].to_numpy()
        assert ((a == b) | (pd.isna(a) & pd.isna(b))).all(), column


def test_a_failing_pair_is_a_row_with_its_error(client, tmp_path):
    table = qm3d.dask.score_pairs([(CLOUD_PAIRS[0][0], tmp_path / "missing.ply"), CLOUD_PAIRS[0]],
                                  client=client, metric="pcqm")
    assert list(table["status"]) == ["error", "ok"]
    assert "missing.ply" in table["error"][0]
    assert pd.isna(table["score"][0])


def test_every_pair_once_when_a_worker_dies(client, tmp_path):
    # 18 distinct pairs (a pair asked for twice is scored once, as in batch).
    pairs = []
    for k in range(6):
        for ref, dist in CLOUD_PAIRS:
            copy = tmp_path / f"{k}_{dist.name}"
            copy.write_bytes(dist.read_bytes())
            pairs.append((ref, copy))
    options = {"radius": 0.02}  # a few tenths of a second per pair
    result = {}

    def run():
        result["table"] = qm3d.dask.score_pairs(pairs, client=client, metric="pcqm", **options)

    worker = threading.Thread(target=run)
    worker.start()
    time.sleep(1.0)  # tasks are running on both workers
    pids = client.run(os.getpid)
    victim = sorted(pids.values())[0]
    os.kill(victim, signal.SIGKILL)
    worker.join(timeout=300)
    assert not worker.is_alive()
    table = result["table"]
    assert len(table) == len(pairs)
    assert (table["status"] == "ok").all(), table["error"].tolist()
    expected = [qm3d.pcqm(r, d, **options).score for r, d in CLOUD_PAIRS]
    assert list(table["score"]) == expected * 6
    assert list(table["distorted"]) == [str(d) for _, d in pairs]


def test_a_pair_that_gets_its_worker_killed_is_its_error_row(tmp_path):
    # One 500 MB worker; the last pair, mesh PSNR on mmetric's grid at size 2048 (about 1.9 GB:
    # millions of grid samples per mesh, past 500 MB within two seconds), takes it past the
    # nanny's terminate threshold (95 %), which kills it. No retry (allowed-failures 0) keeps
    # the test short: Dask gives up on the task at once (KilledWorker), which must be that
    # pair's error row, the other rows kept. (It comes last: tasks queued on a worker that dies
    # count that death too, and with no retry would fail.)
    import dask
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                           memory_limit="500MB", dashboard_address=None)
        c = distributed.Client(cluster)
    try:
        pairs = [(*CLOUD_PAIRS[0], "pcqm"), (*CLOUD_PAIRS[1], "pcqm"), (*MESH_PAIRS[0], "psnr")]
        table = qm3d.dask.score_pairs(pairs, client=c, grid_size=2048, radius=0.02)
    finally:
        c.close()
        cluster.close()
    assert list(table["status"]) == ["ok", "ok", "error"], table["error"].tolist()
    assert list(table["metric"]) == ["pcqm", "pcqm", "psnr"]
    assert "died" in table["error"][2] and "KilledWorker" in table["error"][2]
    assert pd.isna(table["score"][2])
    assert table["score"][0] == qm3d.pcqm(*CLOUD_PAIRS[0], radius=0.02).score
