"""RQ1 end to end: pick the monitors per logical scenario, evaluate them, write the report.

Shared by `evoeye evaluate` and the evaluate flow. Monitors given by version are evaluated on
the logical scenario they were trained on when their card names one, else on every scenario.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from evoeye.evaluation.explain import attribution_shares
from evoeye.evaluation.harness import SCENARIO_KS, EvaluationReport, evaluate
from evoeye.evaluation.monitors import BASELINES, baseline_monitors, load_monitors, train_fusion
from evoeye.evaluation.report import ReportFiles, write_report
from evoeye.monitor.protocol import Monitor
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec, Warehouse


def warehouse_scenarios(root: DataRoot) -> list[str]:
    """The logical scenarios that have runs in the warehouse."""
    return Warehouse(root).query("logical_scenarios").column("logical_scenario").to_pylist()


def trained_on(monitor: Monitor) -> str | None:
    """The logical scenario a trained monitor's card names, if any."""
    card = getattr(monitor, "card", None) or {}
    return card.get("logical_scenario")


def rq1(
    root: DataRoot,
    scenarios: Sequence[str] | None = None,
    *,
    baselines: Sequence[str] = tuple(BASELINES),
    monitor_versions: Sequence[str] = (),
    fusion: bool = False,
    splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
    ks: Sequence[int] = SCENARIO_KS,
    latency: bool = True,
    store_scores: bool = True,
    progress: Callable[[str], None] | None = None,
) -> list[EvaluationReport]:
    """Evaluate the baselines, the given monitor versions and (with `fusion`) a FusionMonitor
    trained for each scenario; one report per logical scenario."""
    scenarios = list(scenarios) if scenarios else warehouse_scenarios(root)
    if not scenarios:
        raise ValueError(f"the warehouse under {root.path} has no runs: ingest some first")
    say = progress or (lambda msg: None)
    loaded = load_monitors(root, monitor_versions)
    reports = []
    for scenario in scenarios:
        monitors: list[Monitor] = [m for m in loaded if trained_on(m) in (None, scenario)]
        if fusion:
            say(f"{scenario}: training the FusionMonitor")
            monitors.append(train_fusion(root, scenario, splits=splits))
        if baselines:
            say(f"{scenario}: preparing baselines {', '.join(baselines)}")
            monitors += baseline_monitors(root, scenario, splits, baselines)
        say(f"{scenario}: evaluating {', '.join(m.name for m in monitors)}")
        reports.append(evaluate(root, monitors, scenario, splits, ks=ks, latency=latency,
                                store_scores=store_scores))
    return reports


def rq1_report(root: DataRoot, reports: Sequence[EvaluationReport],
               name: str | None = None) -> ReportFiles:
    """Write the Markdown, HTML and JSON report of these evaluations, with each logical
    scenario's root-cause shares (`evoeye explain`) when the warehouse has them."""
    dicts = [r.to_dict() for r in reports]
    for d in dicts:
        if shares := attribution_shares(root, d["logical_scenario"]):
            d["attribution"] = shares
    return write_report(root, dicts, name)
