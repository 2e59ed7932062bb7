"""`evoeye reproduce`: every table of docs/results again, in one command, from what it records.

`evoeye findings` writes findings.json with, for each `evoeye results` run it combines, the
run's file and its whole config (`combine`). That is the plan: `reproduce` re-runs each of those
runs with its recorded config — on a data root of its own under a folder, or on a root named for
it — writes its results.json and its Markdown back beside findings.json under the same names,
and combines them again as `evoeye findings` did (findings.md, findings.json, and the README's
findings section). Each run is resumable and idempotent (the ledger of `evoeye results`): a
killed reproduction picks up where it stopped, and on the roots that produced the files it
recomputes nothing and rewrites the same tables.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from evoeye.paths import PLAIN_NAME, DataRoot
from evoeye.results.combine import combine, file_in, write_combined
from evoeye.results.config import MONITOR_PARTS, ResultsConfig
from evoeye.results.study import Progress

FINDINGS_FILE = "findings.json"


class PlanError(ValueError):
    """A findings file that does not say which runs produced it, or a root given for no run."""


@dataclass(frozen=True)
class PlannedRun:
    """One `evoeye results` run of the plan: its name (the file stem), where its results.json
    goes, and its config."""

    name: str
    path: Path
    config: ResultsConfig


def read_plan(path: Path) -> list[PlannedRun]:
    """The runs a findings.json of `evoeye findings` was combined from, each with its config;
    PlanError naming the file and the run that cannot be re-run."""
    file = file_in(path, FINDINGS_FILE)
    try:
        data = json.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise PlanError(f"{file}: no such findings file") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise PlanError(f"{file}: not a findings JSON ({exc})") from None
    sources = data.get("sources") if isinstance(data, dict) else None
    if not isinstance(sources, list) or not sources:
        raise PlanError(f"{file}: no runs recorded (write it with `evoeye findings`)")
    plan: list[PlannedRun] = []
    for source in sources:
        if not isinstance(source, dict) or not isinstance(source.get("path"), str):
            raise PlanError(f"{file}: a run without its results file: {source!r}")
        name = Path(source["path"]).stem
        if not PLAIN_NAME.fullmatch(name):
            raise PlanError(f"{file}: run {source['path']!r} has no plain name")
        if any(p.name == name for p in plan):
            raise PlanError(f"{file}: two runs are named {name!r}")
        try:
            config = ResultsConfig.from_dict(source.get("config") or {})
        except (TypeError, ValueError) as exc:
            raise PlanError(f"{file}: run {name!r} cannot be re-run: {exc}") from None
        plan.append(PlannedRun(name, file.parent / f"{name}.json", config))
    return plan


def run_markdown(results: dict) -> str:
    """The Markdown of a run's parts: RQ1's and the monitor ablation's, RQ2's, the
    sample-efficiency study's, the rare-failure protocol's, or several."""
    from evoeye.results.run import markdown_files

    files = markdown_files(results)
    parts = set(results["config"]["parts"])
    chosen = [f for f, own in (("rq1.md", parts & set(MONITOR_PARTS)), ("rq2.md", "rq2" in parts),
                               ("efficiency.md", "efficiency" in parts),
                               ("rare.md", "rare" in parts)) if own]
    return "\n\n".join(files[f].rstrip("\n") for f in chosen) + "\n"


def reproduce(findings: Path, data: Path, *, roots: Mapping[str, Path] | None = None,
              only: Sequence[str] = (), workers: int | None = None, readme: Path | None = None,
              progress: Progress | None = None) -> str:
    """Re-run the runs of the plan in `findings` — all, or those named in `only` — (on
    `roots[name]`, else `data/<name>`; `workers` replaces the recorded processes), write each
    one's `<name>.json` and `<name>.md` beside the findings file, and combine every run of the
    plan again; findings.md's text. Everything that can be refused is refused before a run."""
    from evoeye.results.run import run_results, write_results

    file = file_in(findings, FINDINGS_FILE)
    plan = read_plan(file)
    names = [run.name for run in plan]
    for given, what in ((roots or {}, "root given"), (only, "--only")):
        if unknown := sorted(set(given) - set(names)):
            raise PlanError(f"{what} for no run of {file}: {unknown}; its runs: {names}")
    chosen = [run for run in plan if not only or run.name in only]
    if kept := [run.path for run in plan if run not in chosen and not run.path.is_file()]:
        raise PlanError(f"{file}: {[str(p) for p in kept]} missing: re-run those runs too, "
                        "or put their results there")
    configs = [run.config if workers is None else replace(run.config, workers=workers)
               for run in chosen]
    for run, config in zip(chosen, configs, strict=True):
        try:
            config.check_names()
        except ValueError as exc:
            raise PlanError(f"{file}: run {run.name!r} cannot be re-run: {exc}") from None
    for run, config in zip(chosen, configs, strict=True):
        root = DataRoot.resolve((roots or {}).get(run.name, Path(data) / run.name))
        results = run_results(root, config, progress).results
        folder = write_results(root, results, run.name)
        shutil.copyfile(folder / "results.json", run.path)
        run.path.with_suffix(".md").write_text(run_markdown(results), encoding="utf-8")
    return write_combined(combine([run.path for run in plan]), file.parent, readme)
