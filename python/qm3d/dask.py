"""Scoring many pairs on a Dask cluster: the rows ``qm3d batch`` writes, as a pandas DataFrame.

Example::

    import qm3d.dask
    table = qm3d.dask.score_pairs([("ref.ply", "d1.ply"), ("ref.ply", "d2.ply")])
    # or on a running cluster:
    from distributed import Client
    table = qm3d.dask.score_pairs(pairs, client=Client("tcp://scheduler:8786"), metric="pcqm")

Each pair (or each metric of a pair, for metric="compare") is one Dask task. A pair that fails
gives a row with status "error" and its message, never a lost batch; a task lost with a dying
worker is run again by Dask, so every row is there exactly once. A pair that takes down every
worker that runs it (a crash, or the nanny killing the worker over its memory limit, on
``distributed.scheduler.allowed-failures`` + 1 workers) is its own error row too, as in
``qm3d batch``: the other pairs' rows are kept.
"""

import math

import pandas as _pd

import qm3d

__all__ = ["score_pairs", "COLUMNS"]

_VALUE_NAMES = qm3d._qm3d.csv_value_names()
COLUMNS = qm3d._qm3d.csv_header(_VALUE_NAMES).split(",")
"""The columns, as in ``qm3d batch``'s CSV (with the named-value columns of every metric)."""

_TEXT_COLUMNS = {"reference", "distorted", "metric", "status", "error", "warnings"}


def _parsed(line):
    """A row made by the bindings (the rows ``qm3d batch`` writes: qm3d::study's csv_row and
    csv_error_row), as a dict of COLUMNS: numbers as floats, empty numbers NaN; an error row's
    empty text cells NaN too."""
    import csv
    fields = next(csv.reader([line]))
    ok = fields[COLUMNS.index("status")] == "ok"
    row = {}
    for name, value in zip(COLUMNS, fields):
        if not value:
            row[name] = "" if ok and name in _TEXT_COLUMNS else math.nan
        else:
            row[name] = value if name in _TEXT_COLUMNS else float(value)
    return row


def _error_row(reference, distorted, metric, message):
    return _parsed(qm3d._qm3d.csv_error_row(str(reference), str(distorted), str(metric),
                                            str(message), _VALUE_NAMES))


def _row(result, reference, distorted):
    row = _parsed(result.csv_row(_VALUE_NAMES))
    row.update(reference=str(reference), distorted=str(distorted))
    return row


def _metrics_of(reference, distorted, metric):
    """The metric names batch would score for this pair (auto: the first that applies, compare:
    all that apply)."""
    if metric not in ("auto", "compare"):
        return [metric]
    ref = qm3d._Inputs(reference, "reference").any()
    dist = qm3d._Inputs(distorted, "distorted").any()
    names = qm3d._qm3d.applicable(ref, dist)
    return names[:1] if metric == "auto" else names


def _score_pair(reference, distorted, metric, options):
    """Runs on a worker: the rows of one pair (one per metric for compare)."""
    try:
        names = _metrics_of(reference, distorted, metric)
    except Exception as e:  # an unreadable file: one error row, as batch writes it
        return [_error_row(reference, distorted, metric, str(e))]
    rows = []
    for name in names:
        try:
            rows.append(_row(qm3d.metric(name, str(reference), str(distorted),
                                         **qm3d._options_for(name, options)),
                             reference, distorted))
        except Exception as e:
            rows.append(_error_row(reference, distorted, name, str(e)))
    return rows


def _pairs_of(pairs, metric):
    if isinstance(pairs, _pd.DataFrame):
        if not {"reference", "distorted"} <= set(pairs.columns):
            raise ValueError("pairs: a DataFrame needs 'reference' and 'distorted' columns")
        metrics = pairs["metric"] if "metric" in pairs.columns else [metric] * len(pairs)
        return [(r, d, m if isinstance(m, str) and m else metric)
                for r, d, m in zip(pairs["reference"], pairs["distorted"], metrics)]
    out = []
    for i, p in enumerate(pairs):
        if isinstance(p, (str, bytes)) or len(p) not in (2, 3):
            raise ValueError(f"pairs[{i}]: expected (reference, distorted[, metric])")
        out.append((p[0], p[1], p[2] if len(p) == 3 and p[2] else metric))
    return out


def _lost_pair_row(reference, distorted, metric, error):
    """The error row of a task Dask gave up on: its workers died running it (KilledWorker), or
    it was cancelled or lost with the cluster."""
    why = f"{type(error).__name__}: {error}"
    if type(error).__name__ == "KilledWorker":
        why = ("the worker scoring this pair died each time (killed over its memory limit, or "
               "crashed); " + why)
    return _error_row(reference, distorted, metric, why)


def _gather_rows(futures, work):
    """Every task's rows in pair order; a task that failed as a whole is its pair's error row
    (client.gather would raise at the first one and lose every other row)."""
    from distributed import wait
    wait(futures)
    rows = []
    for future, (reference, distorted, metric) in zip(futures, work):
        try:
            rows.extend(future.result())
        except Exception as e:  # KilledWorker, CancelledError ...: _score_pair itself never raises
            rows.append(_lost_pair_row(reference, distorted, metric, e))
    return rows


def score_pairs(pairs, client=None, metric="auto", **options):
    """Scores every pair as Dask tasks and returns batch's rows as a DataFrame, in pair order.

    Args:
        pairs: (reference, distorted) or (reference, distorted, metric) file paths, or a
            DataFrame with reference, distorted[, metric] columns (a batch list read by pandas).
        client: a distributed.Client; None starts a LocalCluster of one single-threaded worker
            process per core for the call (and closes it).
        metric: for pairs that name none: a metric (see qm3d.metrics()), "auto" (CMDM for two
            meshes, PCQM otherwise) or "compare" (one row per metric that applies).
        **options: as for the metric functions (e.g. knn=10, scales=2), each metric taking the
            ones it knows (as batch); threads defaults to 1 (one core per task: run as many
            workers as cores).

    Returns:
        pandas.DataFrame with the columns of ``qm3d batch``'s final file (COLUMNS without the
        named-value columns of metrics that did not run), one row per (reference,
        distorted, metric) as batch writes them (a key asked for twice is scored once); failed
        pairs have status "error", their message in "error" and NaN scores.
    """
    from distributed import Client, LocalCluster

    work = _pairs_of(pairs, metric)
    qm3d._check_option_names("score_pairs", options)
    if "weights" in options:
        raise TypeError("score_pairs(): weights apply to one metric; give model= (a model file "
                        "names its metric)")
    options.setdefault("threads", 1)
    own = None
    if client is None:
        import os
        cluster = LocalCluster(n_workers=os.cpu_count() or 1, threads_per_worker=1,
                               processes=True, dashboard_address=None)
        own = client = Client(cluster)
    try:
        futures = client.map(_score_pair, [w[0] for w in work], [w[1] for w in work],
                             [w[2] for w in work], [options] * len(work), pure=False)
        rows = _gather_rows(futures, work)
    finally:
        if own is not None:
            cluster = own.cluster
            own.close()
            cluster.close()
    # As batch: one row per (reference, distorted, metric), the first asked for.
    table = _pd.DataFrame(rows, columns=COLUMNS)
    table = table.drop_duplicates(subset=["reference", "distorted", "metric"],
                                  keep="first").reset_index(drop=True)
    return table[_columns_of(set(table["metric"]))]


def _columns_of(metrics):
    """As batch's final file: of the named-value columns, those of the metrics in `metrics`."""
    used = set()
    for spec in qm3d._qm3d.metrics():
        if spec["name"] in metrics:
            used.update(spec["value_names"])
    return qm3d._qm3d.csv_header([n for n in _VALUE_NAMES if n in used]).split(",")
