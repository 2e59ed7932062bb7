"""The monitor ablation: its variants, and a small real run (one epoch per FusionMonitor)."""

from __future__ import annotations

import json

from evoeye.evaluation.ablation import AblationReport, AblationRow, Variant, run_ablation, variants


def test_paper_variants_l_rows_then_input_rows_at_l5() -> None:
    got = [(v.label, v.context_len, v.inputs) for v in variants()]
    assert got == [
        ("L=1", 1, "all"), ("L=3", 3, "all"), ("L=5", 5, "all"), ("L=7", 7, "all"),
        ("perception", 5, "perception"),
        ("perception+prediction", 5, "perception+prediction"),
        ("perception+prediction+planning", 5, "perception+prediction+planning"),
    ]
    assert variants((1,), ("perception", "all"))[-1] == Variant("all", 5, "all")


def test_small_ablation_trains_evaluates_and_tabulates(eval_root, splits) -> None:
    report = run_ablation(eval_root, ["highway-cut-in"], splits, context_lens=(1,),
                          inputs=("perception",), store_scores=False, epochs=1)
    assert [r.label for r in report.rows] == ["L=1", "perception", "context-only", "where-when",
                                              "ttc", "ttc-2d", "rss", "rss-2s"]
    versions = [r.results["highway-cut-in"]["version"] for r in report.rows]
    assert len(set(versions[:2])) == 2 and all(v.startswith("fusion-") for v in versions[:2])
    assert versions[2].startswith("ctx-") and versions[3].startswith("ww-")  # the controls
    assert [v.split("-")[0] for v in versions[4:]] == ["ttc", "ttc2d", "rss", "rss"]
    assert len(set(versions)) == len(versions)
    md = report.markdown()
    for row in report.rows:
        r = row.results["highway-cut-in"]
        line = next(x for x in md.splitlines() if x.startswith(f"| {row.label} |"))
        assert f"| {100 * r['auroc']:.1f} |" in line and f"| {100 * r['auprc']:.1f} |" in line
    folder = report.write(eval_root, "ablation-test")
    assert json.loads((folder / "ablation.json").read_text())["rows"][0]["context_len"] == 1


def test_an_unreachable_fpr_shows_as_such_in_the_ablation_table() -> None:
    rows = [AblationRow("L=1", 1, "all", {"s": {"f1": 0.5, "reachable": True, "auroc": 0.9,
                                                "auprc": 0.4, "version": "a"}}),
            AblationRow("context-only", 1, "context-only",
                        {"s": {"f1": None, "reachable": False, "auroc": 0.7, "auprc": 0.2,
                               "version": "b"}})]
    md = AblationReport(["s"], 0.05, 0, rows).markdown()
    assert "| L=1 | 50.0 | 90.0 | 40.0 |" in md
    assert "| context-only | n/r | 70.0 | 20.0 |" in md and "n/r: the target FPR" in md
