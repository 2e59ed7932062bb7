"""The demo: what the monitor achieves, on fresh runs, in minutes (`evoeye demo`, `make demo`).

1. Simulate `n` runs of each logical scenario that ships a demo monitor (its
   `ScenarioSpec.demo_monitor`; the others are skipped, and said so) in batch `demo`, and ingest
   them. The shipped monitors (`evoeye.monitor.pretrained`) were trained on other runs (another
   seed), so these are fresh to them.
2. Per scenario, evaluate the shipped FusionMonitor against the rule-based baselines on the test
   runs, every threshold calibrated on the validation runs (`SPLITS`).
3. Per scenario, the shipped monitor in the loop (`demo_loop`): it and TTC-2D each trigger the
   production fallback on the test runs, every operating point chosen on the validation runs;
   collisions prevented and caused, false interventions per hour, the lead, beside the oracle.
4. Per scenario, one round of BlindSpotEvolver from the shipped monitor (G_0): propose
   `evolve_runs` runs where G_0 errs, simulate them, fine-tune G_1 on the demo's training runs
   and the new ones, and assess G_0 and G_1 on the test runs and on G_0's Hard Set.
5. Write the reports (`<root>/reports/demo/`: the evaluation's and the loop's) and the
   plain-words summary (`summary.md` beside them), which the command prints.

The command line and the flow (`flows/demo.py`) run the same steps; this module holds what they
share: the settings, the evaluation, the campaign of each round and the summary.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path

from evoeye.evaluation.baselines import rule_names
from evoeye.evaluation.headline import MIN_COLLISIONS, point_note, summary
from evoeye.evolve.campaign.config import CampaignConfig
from evoeye.evolve.campaign.report import change_words
from evoeye.monitor.pretrained import install, packaged_cards, packaged_versions
from evoeye.paths import DataRoot
from evoeye.results.demo_loop import (
    LOOP_NOTE,
    REPORT_STEM,
    loop_words,
    supervise_demo,
    write_loop_report,
)
from evoeye.scenarios import SCENARIO_SPECS, simulable
from evoeye.store import SplitSpec
from evoeye.store.feedback import RoundRow

BATCH = "demo"
REPORT = "demo"
SUMMARY_FILE = "summary.md"
SPLITS = SplitSpec(seed=0, train_frac=0.3, val_frac=0.2)  # half of the runs are test runs
EVOLVE_RUNS = 4  # runs of the one evolution round, per scenario
EVOLVE_SEED = 0


@dataclass
class DemoResult:
    """What the demo produced: the evaluation dicts, each scenario's rounds and closed-loop
    summary (`demo_loop`), where it all is."""

    root: DataRoot
    reports: list[dict]
    rounds: dict[str, list[RoundRow]] = field(default_factory=dict)
    report_dir: Path | None = None
    loop: dict[str, dict] = field(default_factory=dict)

    def paths(self) -> list[tuple[str, Path]]:
        out = [("MCAP logs (open in Foxglove or Lichtblick)", self.root.runs),
               ("warehouse (Parquet + DuckDB; `evoeye sql`)", self.root.warehouse),
               ("monitors and their cards", self.root.monitors)]
        if self.report_dir is not None:
            out += [("report (Markdown, HTML, JSON)", self.report_dir / "report.html")]
            if self.loop:
                out.append(("the monitor in the loop (Markdown, HTML, JSON)",
                            self.report_dir / f"{REPORT_STEM}.html"))
            out.append(("this summary", self.report_dir / SUMMARY_FILE))
        return out


def runs_of(scenario: str) -> int:
    """The demo's runs of `scenario` by default (its `ScenarioSpec.demo_runs`: enough for
    >= MIN_COLLISIONS test collisions)."""
    return SCENARIO_SPECS[scenario].demo_runs


def shipped_folder(scenario: str) -> Path | None:
    """The folder of the versions shipped with `scenario`'s package, if it ships a monitor."""
    package = simulable(scenario).demo_monitor
    return None if package is None else Path(str(files(package)))


def shipped_version(scenario: str) -> str | None:
    """The version shipped for `scenario`, if any."""
    folder = shipped_folder(scenario)
    return None if folder is None else packaged_versions(folder).get(scenario)


def plan(names: Iterable[str] | None = None) -> tuple[list[str], list[str]]:
    """The demo's scenarios (`names`, default every registered one) split into those that
    ship a monitor and those skipped for shipping none; ScenarioError for an unknown name."""
    run, skipped = [], []
    for name in names or SCENARIO_SPECS:
        (run if shipped_version(name) else skipped).append(name)
    return run, skipped


def skipped_line(skipped: list[str]) -> str:
    """What the demo says of the scenarios it skips."""
    return (f"skipped (no demo monitor shipped; `make demo-monitors` trains one): "
            f"{', '.join(skipped)}")


def shipped_monitor(root: DataRoot, scenario: str) -> str:
    """The version shipped for `scenario`, installed into `root`."""
    version = shipped_version(scenario)
    if version is None:
        raise LookupError(f"no monitor is shipped for {scenario!r}: build them with "
                          "`make demo-monitors`")
    return install(root, version, shipped_folder(scenario))


def evaluate_shipped(root: DataRoot, scenario: str) -> dict:
    """The shipped monitor and the rule-based baselines on the demo's test runs (a report
    dict, `EvaluationReport.to_dict()`); the scores go to monitor_scores."""
    from evoeye.evaluation.rq1 import rq1

    (report,) = rq1(root, [scenario], baselines=rule_names(),
                    monitor_versions=[shipped_monitor(root, scenario)], splits=SPLITS,
                    latency=False)
    return report.to_dict()


def supervise_shipped(root: DataRoot, scenario: str, workers: int = 1) -> dict:
    """The shipped monitor and TTC-2D as triggers of the production fallback on the demo's test
    runs, every operating point chosen on its validation runs (`demo_loop`)."""
    return supervise_demo(root, scenario, shipped_monitor(root, scenario), BATCH, SPLITS,
                          workers)


def campaign_config(root: DataRoot, scenario: str, runs: int = EVOLVE_RUNS) -> CampaignConfig:
    """The demo's evolution round: BlindSpotEvolver from the shipped monitor, `runs` runs,
    fine-tuned by the replay update (the shipped monitor learned from runs this root does not
    hold, which a retraining on this root's runs would forget), kept unless the update beats it
    on validation (docs/evolution.md: one round on a handful of runs can wreck it)."""
    from evoeye.evolve.campaign.config import MAX_RUN_S

    return CampaignConfig(scenario, strategy="evoeye", seed=EVOLVE_SEED,
                          monitor=shipped_monitor(root, scenario), n_round=runs,
                          budget_s=MAX_RUN_S * runs, splits=SPLITS, update="replay",
                          keep_parent=True)


def write_summary(result: DemoResult) -> None:
    """The report files and summary.md under `<root>/reports/demo/`."""
    from evoeye.evaluation.rq1 import write_report

    files = write_report(result.root, result.reports, REPORT)
    result.report_dir = files.folder
    if result.loop:
        write_loop_report(files.folder, list(result.loop.values()))
    (files.folder / SUMMARY_FILE).write_text(summary_text(result) + "\n", encoding="utf-8")


WHICH = ("Which figure is which: 'FusionMonitor' is the monitor shipped with evoeye (trained by "
         "`make demo-monitors` on {runs}; see its card), measured here on this demo's test "
         "runs, which it never saw; its thresholds were set again on this demo's validation "
         "runs, as every monitor's. The evolution round ran here, on this demo's runs.")


def _trained_on(scenarios: Iterable[str]) -> str:
    """"401 training runs (and calibrated on 99 validation runs) of highway-cut-in, …": what
    the shipped monitors were trained on."""
    cards = {s: packaged_cards(folder)[s] for s in scenarios
             if (folder := shipped_folder(s)) is not None}
    return ", ".join(f"{card['data']['train']['runs']} training runs (and calibrated on "
                     f"{card['data']['val']['runs']} validation runs) of {scenario}"
                     for scenario, card in cards.items())


def run_round(root: DataRoot, scenario: str, runs: int = EVOLVE_RUNS) -> list[RoundRow]:
    """The demo's evolution round of `scenario`, run here (the flow runs it as a flow run);
    the campaign's rounds, G_0 first."""
    from evoeye.evolve.campaign.assess import Assessor
    from evoeye.evolve.campaign.loop import Campaign
    from evoeye.store.feedback import read_rounds

    cfg = campaign_config(root, scenario, runs)
    campaign = Campaign(root, cfg, assess=Assessor.of(Campaign(root, cfg)))
    campaign.run(max_rounds=1)
    return read_rounds(root, campaign.campaign_id)


def summary_text(result: DemoResult) -> str:
    """The demo's ending, in plain words: per scenario the headline, then what evolution
    changed; then which figure is which."""
    lines = ["evoeye demo: what the runtime monitor achieves", "",
             point_note(result.reports), ""]
    for report in result.reports:
        lines += summary(report)
        loop = result.loop.get(report["logical_scenario"])
        if loop is not None:
            lines += loop_words(loop)
        rows = result.rounds.get(report["logical_scenario"])
        if rows is not None:
            lines.append(f"  Evolution: {change_words(rows)}")
        lines.append("")
    lines.append(WHICH.format(runs=_trained_on(r["logical_scenario"] for r in result.reports)))
    if result.loop:
        lines.append(LOOP_NOTE)
    if any(r["dataset"]["test"]["violations"] < MIN_COLLISIONS for r in result.reports):
        lines.append(f"Fewer than {MIN_COLLISIONS} test collisions in a scenario: its figures "
                     "carry wide intervals and no monitor is called better there.")
    return "\n".join(lines)
