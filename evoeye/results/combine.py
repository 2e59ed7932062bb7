"""The paper's findings over several `evoeye results` runs: `evoeye findings`.

A study too big for one session or one machine runs its parts separately — RQ1 and the
monitor ablation on one data root, RQ2 and the evolution ablations on another — and each run
writes its own `results.json`. `combine` takes every table from the run that has it and checks
the findings over all of them, exactly as one run over everything would (`check_findings`).
A table (part and scenario) present in two runs is refused by name: which of the two counts
would be a choice, and a choice is what the findings must not depend on.

The sample-efficiency study's and the rare-failure protocol's claims are carried over under
"efficiency" and "rare": runs of one protocol are checked together over all their regimes, and
a regime in two of them is refused by name, for the same reason.

The combined JSON keeps, for each run, its path, its config and the tables it gave, so every
verdict can be traced to the run (seeds, sizes, Test Set) that produced it.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from evoeye.results.efficiency.findings import StudyMergeError, merge_studies
from evoeye.results.findings import check_findings
from evoeye.results.rare.findings import RareMergeError, merge_rare

RESULTS_FILE = "results.json"


class ResultsFileError(ValueError):
    """A results file that cannot be read, or two that claim the same table."""


def file_in(path: Path, name: str = RESULTS_FILE) -> Path:
    """`path` itself, or `path/<name>` for a folder (a report folder, docs/results)."""
    return path / name if path.is_dir() else path


def load_results(path: Path) -> dict:
    """A results JSON written by `evoeye results`, checked for what combining needs."""
    file = file_in(path)
    try:
        results = json.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ResultsFileError(f"{file}: no such results file (give the results.json of an "
                               "`evoeye results` run, or its report folder)") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ResultsFileError(f"{file}: not a results JSON ({exc})") from None
    tables = results.get("tables") if isinstance(results, dict) else None
    if not isinstance(tables, list) or not all(
            isinstance(t, dict) and {"id", "scenario", "comparisons"} <= t.keys()
            for t in tables):
        raise ResultsFileError(f"{file}: not written by `evoeye results` (no tables with an "
                               "id, a scenario and comparisons)")
    return results


def _table_name(table: dict) -> str:
    return f"{table['id']} ({table['scenario']})"


def combine(paths: Sequence[Path]) -> dict:
    """{"sources": [{"path", "config", "tables"}], "tables", "findings"} over the runs."""
    if not paths:
        raise ResultsFileError("give at least one results file")
    sources, tables, owner, studies, rare = [], [], {}, [], []
    for path in paths:
        file = file_in(path)
        results = load_results(file)
        names = []
        for table in results["tables"]:
            key = (table["id"], table["scenario"])
            if key in owner:
                raise ResultsFileError(
                    f"{file}: table {_table_name(table)} is also in {owner[key]}; give each "
                    "part and scenario from one run only")
            owner[key] = file
            tables.append(table)
            names.append(_table_name(table))
        sources.append({"path": str(file), "config": results.get("config", {}),
                        "tables": names})
        if "efficiency" in results:
            studies.append({"path": str(file), **results["efficiency"]})
        if "rare" in results:
            rare.append({"path": str(file), **results["rare"]})
    combined = {"sources": sources, "tables": tables, "findings": check_findings(tables)}
    if studies:
        try:  # a study run regime by regime is checked over all of them
            combined["efficiency"] = merge_studies(studies)
        except StudyMergeError as exc:
            raise ResultsFileError(str(exc)) from None
    if rare:
        try:
            combined["rare"] = merge_rare(rare)
        except RareMergeError as exc:
            raise ResultsFileError(str(exc)) from None
    return combined


def source_lines(sources: list[dict], studies: frozenset[str] = frozenset(),
                 rare: frozenset[str] = frozenset()) -> list[str]:
    """One Markdown bullet per run: its file, the tables it gave and the sizes they rest on
    (`studies`, `rare`: the paths of sample-efficiency study and rare-failure protocol runs,
    whose paper settings mean nothing)."""
    out = []
    for s in sources:
        if not s["tables"] and (s["path"] in studies or s["path"] in rare):
            what = " and ".join(w for w, paths in (("the sample-efficiency study", studies),
                                                   ("the rare-failure protocol", rare))
                                if s["path"] in paths)
            out.append(f"* `{s['path']}`: {what} — its claims are below")
            continue
        cfg = s["config"]
        campaigns = "rq2" in cfg.get("parts", ("rq2",))  # RQ1-only runs have none
        sizes = [f"{label} {len(cfg[key])}" for key, label in (
            ("training_seeds", "training seeds"), ("campaign_seeds", "campaign seeds"))
            if cfg.get(key) and (campaigns or key != "campaign_seeds")]
        sizes += [f"{label} {cfg[key]}" for key, label in (
            ("sim_seed", "sim seed"), ("test_seed", "Test Set seed")) if cfg.get(key) is not None]
        tables = ", ".join(s["tables"]) or "no tables"
        out.append(f"* `{s['path']}`: {tables} — {', '.join(sizes)}")
    return out


def combined_markdown(combined: dict, source: str) -> str:
    """findings.md of combined runs: the runs, then the findings as `evoeye results` shows them."""
    from evoeye.results.efficiency.report import efficiency_findings_markdown, study_words
    from evoeye.results.markdown import findings_markdown
    from evoeye.results.rare.report import rare_findings_markdown, rare_words

    def paths_of(key: str) -> frozenset[str]:
        return frozenset(p for s in combined.get(key, []) for p in s["paths"])

    text = findings_markdown(combined["findings"], source, command="evoeye findings",
                             runs=["Each table comes from one `evoeye results` run:", "",
                                   *source_lines(combined["sources"], paths_of("efficiency"),
                                                 paths_of("rare"))])
    for key, claims, words in (("efficiency", efficiency_findings_markdown, study_words),
                               ("rare", rare_findings_markdown, rare_words)):
        for study in combined.get(key, []):
            paths = ", ".join(f"`{p}`" for p in study["paths"])
            text += (f"\n{claims(study['findings'])}\n"
                     f"From {paths}: {words(study['config'])}.\n")
    return text


def write_combined(combined: dict, out: Path | None = None, readme: Path | None = None) -> str:
    """findings.md (returned; with `out`, written there beside findings.json and RQ1's figure),
    and with `readme`, its summary spliced into the README's findings section."""
    from evoeye.results.readme import write_figure, write_readme_section

    source = str(out / "findings.json") if out is not None else "the runs below"
    text = combined_markdown(combined, source)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        (out / "findings.json").write_text(json.dumps(combined, indent=1) + "\n",
                                           encoding="utf-8")
        (out / "findings.md").write_text(text, encoding="utf-8")
        write_figure(combined["tables"], out)
    if readme is not None:
        write_readme_section(readme, combined["findings"], source,
                             None if out is None else out / "findings.md",
                             command="evoeye findings", studies=combined.get("efficiency", []),
                             rare=combined.get("rare", []))
    return text
