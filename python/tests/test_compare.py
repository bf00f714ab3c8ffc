"""irad.compare runs `irad compare` and returns its table as a list of dicts."""

import json

import irad


def test_compare_returns_the_table_and_the_report(tmp_path):
    t = irad.compare("cornell-orbit", samplers=["cdf", "mh"], vpls=[8], size=(16, 16),
                     frames=range(0, 4), spp=4, out=tmp_path / "out", cache=tmp_path / "cache")
    data = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert [(r["sampler"], r["vpls"]) for r in t] == [("cdf", 8), ("mh", 8)]
    for row, run in zip(t, data["runs"]):
        assert row["mean_rel_mse"] == run["metrics"]["mean_rel_mse"]
        assert row["flicker_f1"] == run["metrics"]["flicker_f1"]
        assert row["warped_f1"] == run["warped"]["f1"]
    assert len(t.frames) == 2 * 4 and t.frames[1]["frame"] == 1
    assert t.floor["flicker_f1"] > 0
    assert (tmp_path / "out" / "report.html").exists() and t.report.endswith("report.html")
