"""The README's findings section is what `evoeye results` generates, never hand-written."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from evoeye.results.combine import combined_markdown
from evoeye.results.findings import check_findings
from evoeye.results.markdown import README_BEGIN, README_END, findings_markdown, splice_readme

REPO = Path(__file__).resolve().parents[2]
RESULTS = REPO / "docs" / "results" / "results.json"
COMBINED = REPO / "docs" / "results" / "findings.json"  # `evoeye findings --out docs/results`


def _section() -> str:
    """What the README's section must be: from docs/results/findings.json when the findings
    combine several runs, else from the one run's results.json."""
    if COMBINED.exists():
        return combined_markdown(json.loads(COMBINED.read_text()), "docs/results/findings.json")
    findings = (json.loads(RESULTS.read_text())["findings"] if RESULTS.exists()
                else check_findings([]))  # before the first run: every finding "not run yet"
    return findings_markdown(findings, "docs/results/results.json")


def test_the_readme_section_is_generated_from_the_results() -> None:
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    assert readme.count(README_BEGIN) == 1 and readme.count(README_END) == 1
    assert splice_readme(readme, _section()) == readme


def test_splicing_replaces_only_the_section() -> None:
    text = f"a\n{README_BEGIN}\nold\n{README_END}\nb\n"
    assert splice_readme(text, "new\n") == f"a\n{README_BEGIN}\nnew\n{README_END}\nb\n"
    with pytest.raises(ValueError, match="no findings section"):
        splice_readme("a\nb\n", "new")
