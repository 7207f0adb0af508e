"""qm3d.evaluate() on several metrics with Krasula's analysis, against the Toyama reference values
of ../shared/data/reference/evaluation (README there)."""
import csv
import math
import os

import pytest

import qm3d

EVAL = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data", "reference",
                    "evaluation")


def rows(name):
    with open(os.path.join(EVAL, name), newline="") as f:
        return list(csv.DictReader(f))


def close(got, expected, rel=1e-12):
    return abs(got - expected) <= rel * abs(expected)


def toyama():
    table = rows("toyama_stimuli_5metrics.csv")
    scores = {f"m{k}": [float(r[f"m{k}"]) for r in table] for k in range(1, 6)}
    return (scores, [float(r["MOS"]) for r in table], [float(r["SD"]) for r in table],
            [float(r["n"]) for r in table])


def test_toyama_every_per_metric_and_pairwise_value():
    scores, mos, sd, n = toyama()
    r = qm3d.evaluate(scores, mos, sd=sd, n=n, bootstrap=0)
    assert r["stimuli"] == 168
    assert r["krasula"]["different"] == 11121 and r["krasula"]["similar"] == 2907
    for e in rows("toyama_vmaf_computed_per_metric.csv"):
        k = r["metrics"]["m" + e["metric"]]["krasula"]
        for ours, theirs in (("auc_ds", "AUC_DS"), ("auc_bw", "AUC_BW"), ("c0", "CC_0"),
                             ("thr", "THR_numpy"), ("thr_prctile", "THR_prctile"),
                             ("se_ds", "SE_DS_DeLong"), ("se_bw", "SE_BW_DeLong")):
            assert close(k[ours], float(e[theirs])), (e["metric"], ours)
    p = {(c["a"], c["b"], c["test"]): c["p"] for c in r["comparisons"]}
    for e in rows("toyama_vmaf_computed_pairwise.csv"):
        if e["metric_a"] == e["metric_b"]:
            continue
        a, b = "m" + e["metric_a"], "m" + e["metric_b"]
        assert abs(p[(a, b, "delong_auc_ds")] - float(e["pDS_DL"])) <= 1e-9
        assert abs(p[(a, b, "delong_auc_bw")] - float(e["pBW_DL"])) <= 1e-9
        assert abs(p[(a, b, "c0")] - float(e["pCC0_b"])) <= 1e-9


def test_vmaf_unit_test_means():
    scores, mos, sd, n = toyama()
    r = qm3d.evaluate(scores, mos, sd=sd, n=n, bootstrap=0)
    means = {q: sum(r["metrics"][m]["krasula"][k] for m in scores) / 5
             for q, k in (("mean(AUC_DS)", "auc_ds"), ("mean(AUC_BW)", "auc_bw"),
                          ("mean(CC_0)", "c0"), ("mean(THR)", "thr"))}
    for e in rows("vmaf_perf_metric_test_expected.csv"):
        if e["test"] == "test_auc_metrics_performance":
            assert round(means[e["quantity"]] - float(e["expected_as_written"]), 6) == 0
            assert close(means[e["quantity"]], float(e["computed"]))


def test_raw_scores_and_given_pairs():
    table = rows("vmaf_rawscore_vector.csv")
    raw = [[float(r[f"score{k}"]) for k in range(1, 11)] for r in table]
    # The logistic fit needs 5 stimuli: a fifth, far better one.
    raw.append([9 + 0.01 * k for k in range(10)])
    a = [float(r["prediction_a"]) for r in table] + [5]
    b = [float(r["prediction_b"]) for r in table] + [5]
    mos = [sum(x) / len(x) for x in raw]
    r = qm3d.evaluate({"a": a, "b": b}, mos, raw=raw, bootstrap=0)
    assert r["krasula"]["pairs"] == 25
    given = qm3d.evaluate({"a": a, "b": b}, mos, bootstrap=0,
                          pairs=[(i, j, 1 if mos[i] > mos[j] + 1 else -1 if mos[j] > mos[i] + 1 else 0)
                                 for i in range(5) for j in range(5) if i != j])
    assert given["krasula"]["rule"] == "given"
    with pytest.raises(ValueError, match="pairs"):
        qm3d.evaluate({"a": a}, mos, pairs=[(0, 7, 1)])


def test_orientation_from_the_registry_and_lower_is_better():
    mos = [1.0, 2.0, 2.9, 4.1, 4.8, 3.3]
    psnr = [20.0, 25.0, 29.0, 36.0, 41.0, 31.0]
    cmdm = [0.4, 0.3, 0.2, 0.1, 0.05, 0.15]
    other = [0.5, 0.4, 0.3, 0.2, 0.1, 0.25]
    sd, n = [0.5] * 6, [20] * 6
    r = qm3d.evaluate({"psnr": psnr, "cmdm": cmdm, "other": other}, mos, sd=sd, n=n,
                      bootstrap=0, lower_is_better=["other"])
    assert r["metrics"]["psnr"]["orientation"]["higher_is_better"] is True
    assert r["metrics"]["cmdm"]["orientation"]["higher_is_better"] is False
    assert r["metrics"]["other"]["orientation"]["from"] == "lower_is_better"
    for m in ("psnr", "cmdm", "other"):
        assert r["metrics"][m]["krasula"]["c0"] == 1.0, m
    assumed = qm3d.evaluate({"other": other, "psnr": psnr}, mos, sd=sd, n=n, bootstrap=0)
    assert "assumed" in assumed["metrics"]["other"]["orientation"]["from"]
    assert assumed["metrics"]["other"]["krasula"]["c0"] == 0.0  # taken as a quality: all wrong


def test_bad_subjective_data():
    scores, mos, sd, n = toyama()
    with pytest.raises(ValueError, match="n"):
        qm3d.evaluate(scores, mos, sd=sd, bootstrap=0)
    with pytest.raises(ValueError, match="fewer than 2 observers"):
        qm3d.evaluate(scores, mos, sd=sd, n=[1] * 168, bootstrap=0)
    with pytest.raises(ValueError, match="one of"):
        qm3d.evaluate(scores, mos, sd=sd, n=n, raw=[[1, 2]] * 168, bootstrap=0)
    with pytest.raises(ValueError, match="NaN"):
        qm3d.evaluate(scores, mos, sd=[math.nan] * 168, n=n, bootstrap=0)


def test_vmafs_four_stimuli_without_the_logistic():
    # VMAF's own raw-score tests have 4 stimuli: enough for correlations and Krasula's analysis
    # with a mapping of 2 parameters or none; the logistic (and the one-metric default) needs 5.
    table = rows("vmaf_rawscore_vector.csv")
    raw = [[float(r[f"score{k}"]) for k in range(1, 11)] for r in table]
    a = [float(r["prediction_a"]) for r in table]
    b = [float(r["prediction_b"]) for r in table]
    mos = [sum(x) / len(x) for x in raw]
    for mapping in ("none", "linear"):
        r = qm3d.evaluate({"a": a, "b": b}, mos, raw=raw, bootstrap=0, mapping=mapping)
        assert r["stimuli"] == 4 and r["krasula"]["pairs"] == 16
        assert r["metrics"]["a"]["mapping"]["name"] == mapping
    one = qm3d.evaluate(a, mos, bootstrap=0, mapping="linear")
    assert one["stimuli"] == 4
    with pytest.raises(ValueError, match="at least 5"):
        qm3d.evaluate(a, mos, bootstrap=0)


def test_a_typo_and_a_self_pair_are_refused():
    mos = [1.0, 2.0, 2.9, 4.1, 4.8, 3.3]
    scores = {"psnr": [20.0, 25.0, 29.0, 36.0, 41.0, 31.0], "other": [5, 4, 3, 2, 1, 2.5]}
    with pytest.raises(ValueError, match="lower_is_better: othr: no such metric"):
        qm3d.evaluate(scores, mos, bootstrap=0, lower_is_better=["othr"])
    with pytest.raises(ValueError, match="paired with itself"):
        qm3d.evaluate(scores, mos, bootstrap=0, pairs=[(0, 1, -1), (2, 2, 0), (3, 1, 1)])
