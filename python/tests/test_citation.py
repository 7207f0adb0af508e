"""CITATION.cff is valid YAML with the keys of the Citation File Format 1.2 (cff-version, message,
title, authors; each reference with a type, a title and authors), and names what qm3d reproduces."""
import os

import yaml

CFF = os.path.join(os.path.dirname(__file__), "..", "..", "CITATION.cff")
REFERENCE_TYPES = {"article", "conference-paper", "software", "standard", "book", "report"}


def load():
    with open(CFF, encoding="utf-8") as f:
        return yaml.safe_load(f)


def test_required_cff_1_2_keys():
    c = load()
    assert c["cff-version"] == "1.2.0"
    for key in ("message", "title", "authors", "version", "type"):
        assert c.get(key), key
    assert c["type"] == "software"
    assert all("name" in a or "family-names" in a for a in c["authors"])


def test_references_cite_the_metrics_and_the_reference_tools():
    refs = load()["references"]
    for r in refs:
        assert r["type"] in REFERENCE_TYPES, r
        assert r["title"] and r["authors"], r
        assert all("name" in a or "family-names" in a for a in r["authors"]), r
    titles = " | ".join(r["title"] for r in refs)
    for needle in ("Diffuse Colors", "PCQM", "Multiscale Metric", "accuracy of objective",
                   "MEPP2", "pc_error"):
        assert needle in titles, needle
