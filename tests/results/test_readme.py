"""The README's findings section is what `evoeye results` / `evoeye findings` generate, never
hand-written: each finding's verdict, linking to findings.md for the comparisons."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from evoeye.results.findings import check_findings
from evoeye.results.markdown import README_BEGIN, README_END, splice_readme
from evoeye.results.readme import FIGURE, readme_section, rq1_figure, write_readme_section

REPO = Path(__file__).resolve().parents[2]
RESULTS = REPO / "docs" / "results" / "results.json"
COMBINED = REPO / "docs" / "results" / "findings.json"  # `evoeye findings --out docs/results`


def _section() -> str:
    """What the README's section must be: from docs/results/findings.json when the findings
    combine several runs, else from the one run's results.json."""
    if COMBINED.exists():
        combined = json.loads(COMBINED.read_text())
        return readme_section(combined["findings"], "docs/results/findings.json",
                              command="evoeye findings", details="docs/results/findings.md",
                              studies=combined.get("efficiency", []),
                              rare=combined.get("rare", []))
    findings = (json.loads(RESULTS.read_text())["findings"] if RESULTS.exists()
                else check_findings([]))  # before the first run: every finding "not run yet"
    return readme_section(findings, "docs/results/results.json",
                          details="docs/results/findings.md")


def test_the_readme_section_is_generated_from_the_results() -> None:
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    assert readme.count(README_BEGIN) == 1 and readme.count(README_END) == 1
    assert splice_readme(readme, _section()) == readme


def test_the_figure_is_drawn_from_the_same_results() -> None:
    source = COMBINED if COMBINED.exists() else RESULTS
    figure = REPO / "docs" / "results" / FIGURE
    tables = json.loads(source.read_text())["tables"]
    assert figure.read_text(encoding="utf-8") == rq1_figure(tables)
    assert f"(docs/results/{FIGURE})" in (REPO / "README.md").read_text(encoding="utf-8")


def test_splicing_replaces_only_the_section() -> None:
    text = f"a\n{README_BEGIN}\nold\n{README_END}\nb\n"
    assert splice_readme(text, "new\n") == f"a\n{README_BEGIN}\nnew\n{README_END}\nb\n"
    with pytest.raises(ValueError, match="no findings section"):
        splice_readme("a\nb\n", "new")


def test_the_section_summarises_each_finding_and_links_to_its_checks(tmp_path: Path) -> None:
    findings = check_findings([])
    readme = tmp_path / "README.md"
    readme.write_text(f"top\n{README_BEGIN}\nold\n{README_END}\n", encoding="utf-8")
    write_readme_section(readme, findings, "x/findings.json", tmp_path / "x" / "findings.md")
    text = readme.read_text(encoding="utf-8")
    assert "[x/findings.md](x/findings.md)" in text and "old" not in text
    rows = [line for line in text.splitlines() if line.startswith("| ") and "**" in line]
    assert [r.split(" | ")[0][2:] for r in rows] == [f["claim"] for f in findings]
    assert all(r.endswith(f"**{f['verdict']}** |") for r, f in zip(rows, findings, strict=True))


def test_several_studies_share_one_heading_each_with_its_own_table() -> None:
    def study(seeds: list[int], verdict: str) -> dict:
        return {"config": {"mode": "pool", "seeds": seeds, "regimes": ["r:cautious"]},
                "findings": [{"claim": "A strategy beats Uniform", "verdict": verdict}]}

    section = readme_section(check_findings([]), "x.json",
                             studies=[study([0, 1], "not shown"), study([100, 101], "reproduces")])
    assert section.count("### Does acquisition earn its budget?") == 1
    assert section.count("| claim | verdict |") == 2
    first = section.index("Study 1 of 2: picked from a pool of pre-simulated uniform runs, "
                          "2 seeds (0–1)")
    second = section.index("Study 2 of 2: picked from a pool of pre-simulated uniform runs, "
                           "2 seeds (100–101)")
    assert first < section.index("**not shown**") < second < section.index("**reproduces**")
