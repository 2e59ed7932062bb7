"""`evoeye results` end to end: the data, RQ1, the monitor ablation and RQ2 of every scenario,
then every table with its CIs, the findings, and the files.

RQ1 and the monitor ablation run on `monitor_study` (the study itself, or one with more initial
runs: `evoeye.results.study`), RQ2 on the study; each scenario's "data" holds the study's
splits and, when RQ1 has its own, "rq1_data" RQ1's.

Resumable and idempotent: the data batches resume, campaigns resume (the experiment API), and
every training, evaluation and assessment is a ledger unit (`evoeye.results.ledger`), so a
re-run does only what is new and writes the same results JSON. Files, under
`<root>/reports/<name>/`: results.json (the one source: per-seed figures, tables, findings),
rq1.md, rq2.md, findings.md and results.html; optionally copied into a docs folder, and the
findings section spliced into a README between its markers.
"""

from __future__ import annotations

import json
import shutil
from collections import Counter
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from evoeye.paths import DataRoot
from evoeye.results.config import MONITOR_PARTS, PAPER_TEST_RUNS, ResultsConfig
from evoeye.results.efficiency.report import efficiency_findings_markdown, efficiency_markdown
from evoeye.results.findings import check_findings
from evoeye.results.html import results_html
from evoeye.results.markdown import findings_markdown, part_markdown
from evoeye.results.rare.report import rare_findings_markdown, rare_markdown
from evoeye.results.readme import write_figure, write_readme_section
from evoeye.results.rq1 import ablation, rq1
from evoeye.results.rq2 import rq2
from evoeye.results.study import Progress, Study, monitor_study, prepare_data, share_logs
from evoeye.results.tables import build_tables
from evoeye.store import Warehouse

PARTS: dict[str, Callable[[Study, str], dict]] = {"rq1": rq1, "ablation": ablation, "rq2": rq2}
DOCS_FILES = ("rq1.md", "rq2.md", "efficiency.md", "rare.md", "findings.md", "results.json")
FINAL_WORDS = {"update": "of its last update",
               "retrain": "of G_0's recipe trained from scratch on its D_R (`--final retrain`: "
                          "what the acquired data is worth, whatever the update rule)"}


@dataclass
class ResultsRun:
    """The results of a run and what its ledger found done and did now, per kind of unit."""

    results: dict
    found: dict[str, int]
    computed: dict[str, int]


def data_summary(study: Study, scenario: str) -> dict:
    """Per split of the initial runs: runs, violations, frames and unsafe frames; the Test Set
    against the paper's."""
    rows = Warehouse(study.root).query("initial_split_stats", logical_scenario=scenario,
                                       horizon_s=study.config.horizon_s,
                                       **asdict(study.splits)).to_pylist()
    splits = {r.pop("split"): r for r in rows}
    return {"splits": splits, "test_batch": study.splits.test_batch,
            "paper_test_runs": PAPER_TEST_RUNS.get(scenario)}


def prepare_studies(root: DataRoot, config: ResultsConfig,
                    progress: Progress | None = None) -> tuple[Study, Study]:
    """The study and the one RQ1 and the ablation run on (the same, or RQ1's own: its logs
    linked from the study's first), their data prepared."""
    study = Study(root, config, progress)
    prepare_data(root, config, progress)
    monitors = monitor_study(study)
    if monitors is not study:
        share_logs(root, monitors.root, monitors.config)
        prepare_data(monitors.root, monitors.config, progress)
    return study, monitors


def part_study(study: Study, monitors: Study, part: str) -> Study:
    """The study a part runs on: RQ1 and the ablation on `monitors`, RQ2 on `study`."""
    return monitors if part in MONITOR_PARTS else study


def scenario_data(study: Study, monitors: Study, scenario: str) -> dict:
    """A scenario's "data" (the study's splits) and, if RQ1 has its own, "rq1_data"."""
    data = {"data": data_summary(study, scenario)}
    if monitors is not study:
        data["rq1_data"] = data_summary(monitors, scenario)
    return data


def run_results(root: DataRoot, config: ResultsConfig,
                progress: Progress | None = None) -> ResultsRun:
    """Prepare the data, run every part of every scenario (and the sample-efficiency study
    over its regimes), and assemble the results."""
    study = monitors = Study(root, config, progress)
    scenarios = {}
    if config.paper_parts:
        study, monitors = prepare_studies(root, config, progress)
        for scenario in config.scenarios:
            parts = scenario_data(study, monitors, scenario)
            for part in config.paper_parts:
                parts[part] = PARTS[part](part_study(study, monitors, part), scenario)
            scenarios[scenario] = parts
    efficiency = None
    if "efficiency" in config.parts:
        from evoeye.results.efficiency.part import run_efficiency

        efficiency = run_efficiency(root, config.efficiency_config, workers=config.workers,
                                    say=progress, ledger=study.ledger)
    ledgers = {id(s.ledger): s.ledger for s in (study, monitors)}.values()
    found = sum((lg.found for lg in ledgers), Counter())
    computed = sum((lg.computed for lg in ledgers), Counter())
    rare = None
    if "rare" in config.parts:  # its curves run in workers, each with a ledger of its own
        from evoeye.results.rare.part import KIND, rare_results

        c = config.rare_config
        rare, now = rare_results(root, c, workers=config.workers, say=progress)
        computed[KIND] += now
        found[KIND] += len(c.regimes) * len(c.seeds) * len(c.strategies) - now - len(
            [f for f in rare["failed"] if not f.get("learning")])
    return ResultsRun(assemble(study, scenarios, efficiency, rare), dict(found),
                      dict(computed))


def assemble(study: Study, scenarios: dict[str, dict], efficiency: dict | None = None,
             rare: dict | None = None) -> dict:
    """The results JSON of a study's parts ({scenario: {"data", part: figures}}, the
    sample-efficiency study's and the rare-failure protocol's): the config, the splits, the
    per-seed figures, every table and the findings (plain JSON types)."""
    tables = build_tables(scenarios)
    results = {"config": study.config.to_dict(), "splits": asdict(study.splits),
               "scenarios": scenarios, "tables": tables, "findings": check_findings(tables)}
    if efficiency is not None:
        results["efficiency"] = efficiency
    if rare is not None:
        results["rare"] = rare
    return json.loads(json.dumps(results, default=float))


def _data_lines(results: dict, key: str = "data") -> list[str]:
    out = ["| scenario | split | runs | violations | frames | unsafe frames |",
           "|---|---|---:|---:|---:|---:|"]
    for scenario, parts in results["scenarios"].items():
        for split, s in parts.get(key, parts["data"])["splits"].items():
            out.append(f"| {scenario} | {split} | {s['scenarios']} | {s['violations']} | "
                       f"{s['frames']:,} | {s['unsafe_frames']:,} |")
    return out


def _intro(results: dict, what: str, data: str = "data") -> str:
    """A part's intro: seeds, splits and the data it ran on (`data`: "data" or "rq1_data")."""
    cfg, splits = results["config"], results["splits"]
    test = (f"the held-out batch `{splits['test_batch']}`" if splits["test_batch"]
            else "the round-0 runs the split seed puts in test")
    own = data != "data" and any(data in p for p in results["scenarios"].values())
    runs = (f"RQ1's own {cfg['rq1_runs']} initial runs per scenario (RQ2's D_init: the "
            f"study's round-0 train split)" if own else "the round-0 runs")
    lines = [f"Generated by `evoeye results` ({what}). Training seeds "
             f"{cfg['training_seeds']}; campaign seeds {cfg['campaign_seeds']}; each final "
             f"monitor judged by the mean over {cfg['final_seeds']} training seeds "
             f"{FINAL_WORDS[cfg.get('final', 'update')]}. Train and "
             f"val: {runs} (shares {splits['train_frac']} : {splits['val_frac']}, "
             f"split seed {splits['seed']}); Test Set: {test}.", "",
             *_data_lines(results, data)]
    return "\n".join(lines)


def _set_lines(results: dict) -> list[str]:
    out = ["| scenario | set | frames | unsafe frames |", "|---|---|---:|---:|"]
    for scenario, parts in results["scenarios"].items():
        for name, size in parts.get("rq2", {}).get("sets", {}).items():
            out.append(f"| {scenario} | {name} | {size['frames']:,} | {size['unsafe']:,} |")
    return out


def markdown_files(results: dict, source: str = "results.json") -> dict[str, str]:
    """File name → Markdown: rq1.md, rq2.md, findings.md (which names `source` as the file the
    findings come from), and efficiency.md when the study ran."""
    rq2_intro = (_intro(results, "RQ2, the evolution ablation and AEM-Evo") + "\n\n"
                 "The sets RQ2 judges on (Hard: the unsafe test frames G_0 misses and the safe "
                 "frames of their runs; Robust Hard: the unsafe test frames a majority of the "
                 "re-seeded G_0s miss and every safe test frame):\n\n"
                 + "\n".join(_set_lines(results)))
    files = {
        "rq1.md": part_markdown("Monitoring effectiveness (RQ1) and the monitor ablation",
                                _intro(results, "RQ1 and the monitor ablation", "rq1_data"),
                                results["tables"], ("rq1", "ablation")),
        "rq2.md": part_markdown("Self-evolution (RQ2), the evolution ablation and AEM-Evo",
                                rq2_intro,
                                results["tables"], ("rq2", "evolution-ablation", "aem-evo",
                                                     "acquisition")),
        "findings.md": findings_markdown(results["findings"], source),
    }
    if "efficiency" in results:
        files["efficiency.md"] = efficiency_markdown(results["efficiency"])
        files["findings.md"] += "\n" + efficiency_findings_markdown(
            results["efficiency"]["findings"])
    if "rare" in results:
        files["rare.md"] = rare_markdown(results["rare"])
        files["findings.md"] += "\n" + rare_findings_markdown(results["rare"]["findings"])
    return files


def write_results(root: DataRoot, results: dict, name: str = "results", *,
                  docs: Path | None = None, readme: Path | None = None) -> Path:
    """Write the files under `<root>/reports/<name>/` (and into `docs`, and the findings'
    summary into the README's section); the report folder."""
    if not name or "/" in name or name.startswith("."):
        raise ValueError(f"report name must be a plain folder name, got {name!r}")
    folder = root.reports / name
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "results.json").write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    source = str(docs / "results.json") if docs is not None else "results.json"
    files = markdown_files(results, source)
    for file, text in files.items():
        (folder / file).write_text(text, encoding="utf-8")
    (folder / "results.html").write_text(results_html(results, f"evoeye results — {name}"),
                                         encoding="utf-8")
    if docs is not None:
        docs.mkdir(parents=True, exist_ok=True)
        for file in DOCS_FILES:
            if (folder / file).is_file():
                shutil.copyfile(folder / file, docs / file)
        write_figure(results["tables"], docs)
    if readme is not None:
        write_readme_section(readme, results["findings"], source,
                             (docs if docs is not None else folder) / "findings.md",
                             studies=[results["efficiency"]] if "efficiency" in results else [],
                             rare=[results["rare"]] if "rare" in results else [])
    return folder
