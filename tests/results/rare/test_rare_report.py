"""rare.md and the claims' section of findings.md, rendered from the `rare` part alone."""

from __future__ import annotations

from rare_curves import COMMON, RARE, rare_curves, rare_part

from evoeye.results.rare.report import (
    HEADING,
    OPEN,
    interval,
    num,
    rare_findings_markdown,
    rare_html,
    rare_markdown,
    rare_words,
    regime_markdown,
)
from evoeye.results.rare.summary import found_pooled


def assert_tables_aligned(text: str) -> None:
    """Every line of a Markdown table has its header's columns (no stray "|" in a cell)."""
    widths: list[int] = []
    for line in [*text.splitlines(), ""]:
        if line.startswith("|"):
            widths.append(line.count("|"))
            continue
        assert len(set(widths)) <= 1, widths
        widths = []


def _row(text: str, first: str) -> str:
    return next(line for line in text.splitlines() if line.startswith(f"| {first} |"))


def test_numbers_use_a_true_minus_and_open_ends_read_infinite():
    assert num(-0.004, 2) == "0.00" and num(-1.5, 1, signed=True) == "−1.5"
    assert num(float("nan")) == "–"  # a figure one seed cannot define
    assert interval(2.5, 1.0, None, open_ends=True, prefix="×") == f"×2.50 [1.00, {OPEN}]"
    assert interval(None, None, None, open_ends=True) == f"– [{OPEN}, {OPEN}]"
    assert interval(None, 1.0, 2.0) == "–" and interval(3.0, None, None) == "3.00"


def test_rare_md_has_every_table_per_regime(two_regimes):
    text = rare_markdown(two_regimes)
    assert text.startswith("# Rare failures")
    assert_tables_aligned(text)
    assert "20 seeds (0–19)" in text and "data seed 9100" in text
    assert "unbiased by construction where a strategy's runs carry their exact p/q" in text
    assert "## highway-cut-in, cautious ADS" in text
    assert "## occluded-crossing, cautious ADS" in text
    rare = text.split("## occluded-crossing")[0]
    found = _row(rare, "ce-is")  # the first ce-is row: failures found
    assert "| 20 | 4000 | 200 | 20 | 5.00 [" in found and "| ×25.00 [" in found
    assert "+4.80 [" in found  # 5 per 100 against 0.2, paired per seed
    assert "Reference P = Uniform's pooled share, 8 of 4000 runs collided: 0.200 % [" in rare
    estimate = [line for line in rare.splitlines() if line.startswith("| ce-is |")][1]
    assert "0.200 % [" in estimate and "| ×8.66 [" in estimate
    uniform = _row(rare, "uniform (reference)")
    cells = [c.strip() for c in uniform.split("|")[2:7]]
    assert cells[:3] == ["20", "4000", "8"] and cells[4].startswith("0.20 [")
    assert 1 <= int(cells[3]) <= 8  # of distinct θ: one θ per synthetic curve
    assert "* ce-is: cut-in / perception (200)" in rare
    common = text.split("## occluded-crossing")[1]
    assert "No estimate" not in common and "| sobol |" in common
    assert "* sobol: crossing / perception (40)" in common


def test_a_regime_with_no_curve_and_failed_curves_are_said_so():
    empty = {"found": {}, "estimates": {}, "distinct": {}}
    text = regime_markdown(RARE, empty, 200, [{"regime": RARE, "strategy": "ce-is", "seed": 3,
                                              "error": "RuntimeError: planted"}])
    assert "No curve of this regime finished." in text
    assert "* ce-is, seed 3: RuntimeError: planted" in text


def test_the_claims_section_lists_each_check(two_regimes):
    text = rare_findings_markdown(two_regimes["findings"])
    assert text.startswith(HEADING)
    assert "| A strategy finds ≥ 10× Uniform's failures per run where failures are ≈ 0.1 % " \
           "(≥ 3× at ≈ 1 %) | **partly** |" in text
    found = _row(text, RARE)
    assert "| ce-is | 0.200 % | ×10 | ×25.00 [" in found and found.endswith("| reproduces |")
    assert _row(text, COMMON).endswith("| ×3 | ×1.00 [1.00, 1.00] | +0.00 [+0.00, +0.00] p=1 "
                                       "| does not reproduce |")
    assert "| bias, points [95 % CI] |" in text
    assert_tables_aligned(text)


def test_a_protocol_is_named_by_its_runs_seeds_and_regimes(two_regimes):
    assert rare_words(two_regimes["config"]) == (
        f"200 runs per seed and strategy (data seed 9100), 20 seeds (0–19), regimes {RARE}, "
        f"{COMMON}")
    merged = {**two_regimes["config"], "seeds": {RARE: [0, 1], COMMON: [5, 6, 7]}}
    assert rare_words(merged).endswith(f"regimes {RARE} (2 seeds (0–1)), {COMMON} (3 seeds "
                                       "(5–7))")
    assert rare_part({RARE: "rare"})["config"]["regimes"] == [RARE]


def test_the_html_part_shows_the_claims_and_a_chart_per_regime(two_regimes):
    html = "".join(rare_html(two_regimes))
    assert html.count("<svg") == 2 and "<h2>Rare failures</h2>" in html
    assert "highway-cut-in, cautious ADS: failures found" in html and "partly" in html


def test_the_pooled_uniform_rate_is_a_line_under_the_failures_found(two_regimes):
    summary = dict(two_regimes["regimes"][RARE])
    summary["found_pooled"] = found_pooled(rare_curves(), 40_000, 40)
    text = regime_markdown(RARE, summary, 200)
    line = next(x for x in text.splitlines() if x.startswith("Against a tighter Uniform rate"))
    assert ("(40000 uniform runs of another seed, 40 collisions): 48 collisions in 44000 runs"
            in line)
    assert "0.109 % [" in line and "ce-is ×45.83 [" in line
    assert text.index("### Failures found") < text.index(line) < text.index(
        "### The failure rate under p")


def test_the_stretches_of_the_curves_are_a_line_under_the_failures_found(two_regimes):
    summary = dict(two_regimes["regimes"][RARE])
    summary["found"] = {name: {**f, "by_stretch": [0.5, 2.25]}
                        for name, f in summary["found"].items()}
    text = regime_markdown(RARE, summary, 200)
    line = next(x for x in text.splitlines() if x.startswith("Where in the curve"))
    assert "runs 1–100, 101–200, …" in line and "uniform 0.50, 2.25" in line
    assert text.index("### Failures found") < text.index(line) < text.index(
        "### The failure rate under p")
    one = {name: {**f, "by_stretch": [0.5]} for name, f in summary["found"].items()}
    assert "Where in the curve" not in regime_markdown(RARE, {**summary, "found": one}, 100)
