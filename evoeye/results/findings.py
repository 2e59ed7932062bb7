"""The paper's findings, each checked against the comparisons of the results tables.

A finding names its table, the metrics and sets it is about and the comparisons (a, b) it
claims; each check is one comparison on one scenario, set and metric, and gets a verdict:

* a "better" claim (a beats b) **reproduces** when the mean paired difference is positive, its
  95 % CI lies above 0 and the Wilcoxon p ≤ 0.05; it is **reversed** when all three say the
  opposite; otherwise it is **not shown** (with the seed pairs given, p cannot fall below
  2 / 2^n: a design too small to decide says so);
* a "little" claim (a gains little over b) **reproduces** when the CI's upper end stays below
  +5 points (the difference the design is sized for), and **does not reproduce** when its lower
  end is at or above +5 points; otherwise it is not shown.

A finding reproduces when every check does — on every scenario its part (rq1, ablation, rq2)
ran on, with every comparison it names (a method or baseline left out of the run, e.g. RQ2 run
on a scenario without aem-evo, leaves it partly shown at best);
does not reproduce when one is reversed (or, for "little", does not reproduce); is partly shown
when some reproduce and none goes against it; and is not run yet when the results have none of
its comparisons.
"""

from __future__ import annotations

from dataclasses import dataclass

from evoeye.results.config import BASELINES
from evoeye.results.rq1 import FUSION_LABEL
from evoeye.results.rq2 import g0_label
from evoeye.results.tables import EFFECT, TABLES, cell_key

ALPHA = 0.05
REPRODUCES, REVERSED, NOT_SHOWN, AGAINST = "reproduces", "reversed", "not shown", \
    "does not reproduce"
PARTLY, NOT_RUN = "partly", "not run yet"


@dataclass(frozen=True)
class Finding:
    """One of the paper's findings and the comparisons that test it."""

    id: str
    claim: str
    paper: str  # what the paper reports
    table: str  # a TableSpec id
    sets: tuple[str, ...]
    metrics: tuple[str, ...]
    pairs: tuple[tuple[str, str], ...]  # (a, b): a beats b ("better"), or gains little on b
    kind: str = "better"


FINDINGS: tuple[Finding, ...] = (
    Finding("rq1-baselines", "The FusionMonitor beats every baseline (RQ1)",
            "best F1, AUROC and AUPRC on both scenarios", "rq1", ("test",),
            ("f1@0.05", "auprc"),
            tuple((FUSION_LABEL, b) for b in BASELINES)),
    Finding("rq3-context", "Monitor ablation: a context of L = 5 frames beats L = 1",
            "F1@0.05 +7.6 (S1), +4.0 (S2)", "ablation", ("test",), ("f1@0.05",),
            (("L=5", "L=1"),)),
    Finding("rq3-inputs", "Monitor ablation: all module inputs beat perception only",
            "F1@0.05 +1.8 (S1), +5.8 (S2)", "ablation", ("test",), ("f1@0.05",),
            (("L=5", "perception"),)),
    Finding("rq2-hard", "EvoEye beats Uniform and AV-Fuzzer on the Hard Set (RQ2)",
            "Hard F1 +10.5–13.2 (S1), +5.7–8.5 (S2) over the strongest baseline", "rq2",
            ("hard", "robust"), ("f1@0.05",), (("evoeye", "uniform"), ("evoeye", "avfuzzer"))),
    Finding("rq3-feedback", "Evolution ablation: feedback helps (EvoEye beats w/o feedback)",
            "Test F1@0.05 34.4 vs 30.6 (S1), 71.5 vs 68.2 (S2)", "evolution-ablation",
            ("test",), ("f1@0.05",), (("evoeye", "no-feedback"),)),
    Finding("rq3-density", "Evolution ablation: density helps (EvoEye beats w/o density)",
            "Test F1@0.05 34.4 vs 28.6 (S1), 71.5 vs 70.8 (S2)", "evolution-ablation",
            ("test",), ("f1@0.05",), (("evoeye", "no-density"),)),
    Finding("rq3-aem-evo", "AEM-Evo gains little over the AEM",
            "Test F1@0.05 7.5 → 6.6 (S1), 27.2 → 28.7 (S2)", "aem-evo", ("test",),
            ("f1@0.05",), (("aem-evo", g0_label("aem")),), kind="little"),
)


def check_verdict(cell: dict, kind: str) -> str:
    """The verdict of one comparison cell (`compare_paired`'s fields; module doc)."""
    diff, low, high, p = cell["mean_diff"], cell["ci_low"], cell["ci_high"], cell["p_value"]
    if diff is None or low is None or high is None:
        return NOT_SHOWN
    if kind == "little":
        return REPRODUCES if high < EFFECT else AGAINST if low >= EFFECT else NOT_SHOWN
    if p is not None and p <= ALPHA and diff > 0 and low > 0:
        return REPRODUCES
    if p is not None and p <= ALPHA and diff < 0 and high < 0:
        return REVERSED
    return NOT_SHOWN


def _overall(verdicts: list[str], missing: int) -> str:
    """A finding's verdict from its checks' (`missing`: checks whose comparison did not run)."""
    if not verdicts:
        return NOT_RUN
    if any(v in (REVERSED, AGAINST) for v in verdicts):
        return AGAINST
    if all(v == REPRODUCES for v in verdicts) and not missing:
        return REPRODUCES
    return PARTLY if REPRODUCES in verdicts else NOT_SHOWN


def check_findings(tables: list[dict]) -> list[dict]:
    """Every finding with its checks (scenario, set, metric, a, b, the comparison cell and its
    verdict) and an overall verdict."""
    part_of = {spec.id: spec.part for spec in TABLES}
    out = []
    for f in FINDINGS:
        # every scenario whose part ran owes the finding its checks, with or without its table
        # (no AEM-Evo table where the part ran without aem-evo: its checks are missing)
        ran = {t["scenario"] for t in tables if part_of.get(t["id"]) == part_of[f.table]}
        checks, expected = [], len(ran) * len(f.pairs) * len(f.sets) * len(f.metrics)
        for table in (t for t in tables if t["id"] == f.table):
            for comparison in table["comparisons"]:
                if (comparison["a"], comparison["b"]) not in f.pairs:
                    continue
                for s in f.sets:
                    for m in f.metrics:
                        cell = comparison["cells"].get(cell_key(s, m))
                        if cell is not None:
                            checks.append({"scenario": table["scenario"], "set": s,
                                           "metric": m, "a": comparison["a"],
                                           "b": comparison["b"], "cell": cell,
                                           "verdict": check_verdict(cell, f.kind)})
        missing = expected - len(checks)
        out.append({"id": f.id, "claim": f.claim, "paper": f.paper, "kind": f.kind,
                    "checks": checks, "missing": missing,
                    "verdict": _overall([c["verdict"] for c in checks], missing)})
    return out
