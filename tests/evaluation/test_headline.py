"""The headline: the figures an engineer asks for first, and no claim the runs cannot carry."""

from __future__ import annotations

import pytest

from evoeye.evaluation.headline import (
    BEST_RULE,
    MIN_COLLISIONS,
    best_rule,
    headline_table,
    operating_point,
    summary,
)
from evoeye.evaluation.report import markdown_report
from evoeye.evaluation.scenario import FalseAlarms, LeadTimes

HOUR_PER_RUN = 0.005  # 18 s of safe driving per run


def monitor(name: str, warned: int, collisions: int, false_per_run: list[int],
            reachable: bool = True, lead0_s: float = 1.0) -> dict:
    ids = [f"v{i}" for i in range(collisions)]
    lead = LeadTimes(warned, collisions, [lead0_s + 0.1 * i for i in range(warned)],
                     ids[:warned])
    fa = FalseAlarms(sum(false_per_run), len(false_per_run), sum(e > 0 for e in false_per_run),
                     HOUR_PER_RUN * len(false_per_run), false_per_run,
                     [HOUR_PER_RUN] * len(false_per_run))
    point = {"0.05": {"reachable": reachable}}
    return {"name": name, "scenario": {"3": {"at_fpr": point,
                                             "lead_time": {"0.05": lead.to_dict()},
                                             "false_alarms": {"0.05": fa.to_dict()}}}}


def report(*monitors: dict, collisions: int, safe: int) -> dict:
    return {"logical_scenario": "highway-cut-in", "fprs": [0.05], "ks": [3],
            "frame_period_s": 0.05, "monitors": list(monitors),
            "dataset": {"test": {"scenarios": collisions + safe, "violations": collisions}}}


def test_the_operating_point_is_said_in_words() -> None:
    r = report(monitor("ttc", 1, 2, [0, 0]), collisions=2, safe=2)
    words = operating_point(r).words()
    assert "5 % of their safe frames alarm" in words
    assert "3 consecutive alarm frames (0.15 s)" in words


def test_too_few_collisions_are_named_and_no_monitor_is_called_better() -> None:
    r = report(monitor("fusion", 4, 4, [0] * 6), monitor("ttc", 0, 4, [3] * 6),
               collisions=4, safe=6)
    text = "\n".join(summary(r))
    assert "warned of 4 of 4 collisions" in text and "TTC warned of 0 of 4" in text
    assert "4 test collisions: too few to compare" in text
    assert "more collisions" not in text and "fewer collisions" not in text
    assert MIN_COLLISIONS > 4


def test_a_clear_difference_on_the_same_runs_is_called_one() -> None:
    n = 20
    r = report(monitor("fusion", 18, n, [0] * 30), monitor("ttc", 8, n, [1] * 30),
               monitor("rss", 5, n, [0] * 30), monitor("aem", 20, n, [9] * 30),
               collisions=n, safe=30)
    text = "\n".join(summary(r))
    assert f"Best rule-based baseline ({BEST_RULE}), TTC warned of 8 of 20" in text  # AEM: no rule
    assert "FusionMonitor warns of more collisions than TTC" in text
    assert "0 (≤ 20.0) false alarms per hour" in text  # 0 in 0.15 h: at most 3.0 / 0.15 h
    assert "200.0 (200.0–200.0) false alarms per hour" in text  # one per 18 s run


def test_a_small_difference_is_not_called_one() -> None:
    n = 20
    r = report(monitor("fusion", 12, n, [0] * 10), monitor("ttc", 11, n, [0] * 10),
               collisions=n, safe=10)
    assert "no clear difference" in "\n".join(summary(r))


def test_monitors_that_warn_alike_are_told_apart_by_false_alarms_only_when_clear() -> None:
    n = 20
    quiet, noisy = monitor("fusion", n, n, [0] * 40), monitor("ttc", n, n, [3] * 40)
    text = "\n".join(summary(report(quiet, noisy, collisions=n, safe=40)))
    assert "no clear difference in collisions warned of" in text
    assert "FusionMonitor raises fewer false alarms per hour than TTC" in text
    assert "their 95 % intervals apart" in text and "warns earlier" not in text  # same leads
    close = monitor("ttc", n, n, [0] * 39 + [1])  # one false alarm: intervals overlap
    text = "\n".join(summary(report(quiet, close, collisions=n, safe=40)))
    assert "no clear difference" in text and "false alarms per hour than" not in text
    late = monitor("ttc", n, n, [0] * 39 + [1], lead0_s=-1.5)  # every warning 2.5 s later
    text = "\n".join(summary(report(quiet, late, collisions=n, safe=40)))
    assert "FusionMonitor warns earlier (median lead" in text


def test_the_best_rule_warns_of_most_then_raises_fewest_false_alarms() -> None:
    r = report(monitor("ttc", 5, 10, [2, 0]), monitor("rss", 5, 10, [1, 0]),
               monitor("ttc-2d", 4, 10, [0, 0]), monitor("rss-2s", 9, 10, [0, 0],
                                                          reachable=False),
               collisions=10, safe=2)
    assert best_rule(r, operating_point(r)).name == "rss"


def test_the_headline_table_fits_the_artifact_view_and_marks_unreachable_points() -> None:
    r = report(monitor("fusion", 7, 9, [0, 1, 0]), monitor("context-only", 9, 9, [0, 0, 0],
                                                           reachable=False),
               collisions=9, safe=3)
    table = headline_table(r)
    assert table.fits(), table.width_chars()
    fusion, control = table.rows
    assert fusion[:2] == ["FusionMonitor", "7 of 9"] and fusion[-1] == "1 of 3"
    assert set(control[1:]) == {"n/r"}


@pytest.mark.parametrize("collisions", [3, 12])
def test_the_markdown_report_opens_with_the_headline(collisions: int) -> None:
    r = report(monitor("fusion", 2, collisions, [0, 1]), monitor("ttc", 1, collisions, [0, 0]),
               collisions=collisions, safe=2)
    for m in r["monitors"]:  # the details tables read frame-level and K=3 figures
        m.update(version=f"{m['name']}-0", context_len=5, thresholds={"0.05": 0.5},
                 val_fpr={"0.05": 0.05}, reachable={"0.05": True}, latency=None,
                 frame={"at_fpr": {"0.05": {"precision": 0.5, "recall": 0.5, "f1": 0.5}},
                        "auroc": 0.9, "auprc": 0.5})
        m["scenario"]["3"].update(auroc=0.8, auprc=0.6)
        m["scenario"]["3"]["at_fpr"]["0.05"].update(precision=1.0, recall=0.5, f1=0.6)
    r["dataset"]["val"] = {"scenarios": 4, "violations": 1, "frames": 100, "unsafe_frames": 10}
    r["dataset"]["test"].update(frames=300, unsafe_frames=30)
    md = markdown_report([r])
    assert md.startswith("# Monitoring effectiveness (RQ1)\n\nOperating point: ")
    assert md.index("FusionMonitor warned of 2 of") < md.index("## Details")
    tables = [line for line in md.splitlines() if line.startswith("| ")]
    assert max(len(line) for line in tables) <= 100  # no sideways scrolling
