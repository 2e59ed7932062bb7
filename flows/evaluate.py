"""Flow: the evaluation (paper RQ1; a thin wrapper): one task per logical scenario, then the
report.

Writing monitor_scores takes the warehouse writer lock, so a task is retried only while another
writer holds it; the report (its headline first) is published as a Markdown artifact.
"""

from __future__ import annotations

from typing import Any

from prefect import flow, get_run_logger, task
from pydantic import BaseModel, Field

from evoeye.evaluation.monitors import BASELINES
from evoeye.evaluation.report import markdown_report, write_report
from evoeye.evaluation.rq1 import rq1, warehouse_scenarios
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec
from flows.published import named, publish
from flows.runners import retry_while_locked


class EvaluateParams(BaseModel):
    """What to evaluate and where (validated before anything runs)."""

    root: str | None = None  # default: $EVOEYE_HOME or ./evoeye-data
    scenarios: list[str] = Field(default_factory=list)  # default: all in the warehouse
    monitors: list[str] = Field(default_factory=list)  # trained monitor versions
    baselines: list[str] = Field(default_factory=lambda: list(BASELINES))
    train_fusion: bool = False
    split_seed: int = Field(SplitSpec().seed, ge=0)
    train_frac: float = Field(SplitSpec().train_frac, ge=0.0, le=1.0)
    val_frac: float = Field(SplitSpec().val_frac, ge=0.0, le=1.0)
    test_batch: str | None = None  # a round-0 batch held out as the Test Set
    latency: bool = True
    report_name: str | None = None

    @property
    def splits(self) -> SplitSpec:
        return SplitSpec(self.split_seed, self.train_frac, self.val_frac, self.test_batch)

    def run_name(self) -> str:
        return f"evaluate-{'-'.join(self.scenarios) or 'all'}"

    def model_post_init(self, __context) -> None:
        self.splits  # noqa: B018  (validates the fractions)
        unknown = [b for b in self.baselines if b not in BASELINES]
        if unknown:
            raise ValueError(f"unknown baseline(s) {unknown}; known: {sorted(BASELINES)}")


@task(retries=5, retry_delay_seconds=10, retry_condition_fn=retry_while_locked,
      task_run_name="evaluate-{scenario}")
def evaluate_scenario(root: DataRoot, scenario: str, params: EvaluateParams) -> dict[str, Any]:
    """The RQ1 figures of one logical scenario (EvaluationReport as a dict)."""
    (report,) = rq1(root, [scenario], baselines=params.baselines,
                    monitor_versions=params.monitors, fusion=params.train_fusion,
                    splits=params.splits, latency=params.latency)
    return report.to_dict()


@flow(name="evoeye-evaluate", log_prints=True,
      flow_run_name=named(lambda p: (p or EvaluateParams()).run_name()))
def evaluate_flow(params: EvaluateParams | None = None) -> dict[str, Any]:
    """Evaluate every scenario, write the report, publish the RQ1 table as an artifact."""
    params = params or EvaluateParams()
    root = DataRoot.resolve(params.root)
    scenarios = params.scenarios or warehouse_scenarios(root)
    # one after the other: each task writes monitor_scores under the single writer lock
    reports = [evaluate_scenario(root, s, params) for s in scenarios]
    files = write_report(root, reports, params.report_name)
    publish("evoeye-rq1", markdown_report(reports), f"evaluation report, {files.html}")
    get_run_logger().info("evaluation report for %s: %s", ", ".join(scenarios), files.html)
    return {"reports": reports, "report_dir": str(files.folder)}


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(EvaluateParams, evaluate_flow, __doc__)
