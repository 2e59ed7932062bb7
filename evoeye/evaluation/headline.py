"""The headline of an evaluation: what a safety engineer asks first, per logical scenario.

One operating point (`operating_point`): every monitor's threshold is the one calibrated on
validation for the first target FPR, and a warning is the largest K of consecutive alarm frames
evaluated. At it, per monitor: the collisions warned of (with the Wilson interval of the
share), the median lead time, the false alarms per hour of safe driving and the safe runs that
raised one (bootstrap intervals over runs; `evoeye.evaluation.scenario`). The plain-words
summary compares the trained monitor with the best rule-based baseline on the same runs, and
calls neither better when the test split holds fewer than `MIN_COLLISIONS` collisions or the
paired test does not separate them (docs/reports.md).
"""

from __future__ import annotations

from dataclasses import dataclass

from evoeye.evaluation.baselines import BASELINE_SPECS, rule_names
from evoeye.evaluation.monitors import BASELINES
from evoeye.evaluation.stats import paired_warnings_p
from evoeye.evaluation.table import DASH, UNREACHABLE, Table, with_ci
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES
from evoeye.scenarios import SCENARIO_SPECS

MIN_COLLISIONS = 10  # fewer test collisions: figures with intervals, but no "better than"
ALPHA = 0.05  # the paired test's level for "warns of more collisions than"
def label(name: str) -> str:
    """How reports name a monitor ("fusion" → "FusionMonitor", a baseline by its spec's label,
    else its name)."""
    if name == DEFAULT_FAMILY:
        return FAMILIES[DEFAULT_FAMILY].label
    spec = BASELINE_SPECS.get(name)
    return name if spec is None else spec.label


@dataclass(frozen=True)
class Point:
    """Where the headline is read: a target FPR and K, as the report dict's keys."""

    fpr: str
    k: str
    period_s: float | None = None  # the frame period, for saying how long K frames last

    def words(self) -> str:
        span = f" ({int(self.k) * self.period_s:.2f} s)" if self.period_s else ""
        frames = "1 alarm frame" if self.k == "1" else f"{self.k} consecutive alarm frames"
        return (f"each monitor's alarm threshold is set on validation runs so that "
                f"{100 * float(self.fpr):g} % of their safe frames alarm (target FPR "
                f"{self.fpr}); a warning is {frames}{span}")


def operating_point(report: dict) -> Point:
    """The headline's point: the first target FPR, the largest K."""
    return Point(str(report["fprs"][0]), str(max(report["ks"])), report.get("frame_period_s"))


@dataclass(frozen=True)
class Figures:
    """One monitor's headline figures (dicts as in the report JSON)."""

    name: str
    reachable: bool
    warned: int
    collisions: int
    warned_ids: frozenset[str]
    recall: dict
    lead: dict
    false_alarms: dict  # FalseAlarms.to_dict()


def figures(monitor: dict, point: Point) -> Figures:
    sc = monitor["scenario"][point.k]
    lt = sc["lead_time"][point.fpr]
    return Figures(monitor["name"], sc["at_fpr"][point.fpr].get("reachable", True),
                   lt["detected"], lt["violations"], frozenset(lt.get("warned_ids", ())),
                   lt["recall"], lt["median"], sc["false_alarms"][point.fpr])


def ranked(f: Figures) -> tuple:
    """Sort key, best first: most collisions warned, fewest false alarms / h, longest lead."""
    per_h = f.false_alarms["per_h"]["value"]
    lead = f.lead["value"]
    return (not f.reachable, -f.warned, float("inf") if per_h is None else per_h,
            -(lead or 0.0))


BEST_RULE = "the rule that warned of the most collisions; ties: fewer false alarms, longer lead"


def best_rule(report: dict, point: Point) -> Figures | None:
    """The best rule-based baseline evaluated (`ranked`), if any was."""
    rules = [figures(m, point) for m in report["monitors"] if m["name"] in rule_names()]
    return min(rules, key=ranked) if rules else None


def trained(report: dict, point: Point) -> list[Figures]:
    """The monitors that are not baselines (FusionMonitor versions), in report order."""
    return [figures(m, point) for m in report["monitors"] if m["name"] not in BASELINES]


def headline_table(report: dict) -> Table:
    """Per monitor: warned collisions, recall, lead time, false alarms / h, alarmed safe runs."""
    point = operating_point(report)
    rows = []
    for m in report["monitors"]:
        f = figures(m, point)
        fa = f.false_alarms
        if not f.reachable:
            rows.append([label(f.name), UNREACHABLE, UNREACHABLE, UNREACHABLE, UNREACHABLE,
                         UNREACHABLE])
            continue
        rows.append([label(f.name), f"{f.warned} of {f.collisions}", with_ci(f.recall, "%"),
                     with_ci(f.lead), with_ci(fa["per_h"]),
                     f"{fa['alarmed_runs']} of {fa['safe_runs']}"])
    return Table(["Monitor", "Warned", "Warned % (CI)", "Lead s (CI)", "False al./h (CI)",
                  "Safe runs al."], rows)


def _few(n: int) -> bool:
    return n < MIN_COLLISIONS


def dataset_words(report: dict, point: Point) -> str:
    """"40 test runs (…): 8 with a collision, 32 collision-free (0.15 h of driving); …": the
    runs measured, and the validation runs the thresholds were set on (a report counts the
    runs of each split apart: the test runs are never the validation ones)."""
    test, val = report["dataset"]["test"], report["dataset"].get("val")
    fa = figures(report["monitors"][0], point).false_alarms if report["monitors"] else None
    hours = f" ({fa['safe_h']:.2f} h of driving)" if fa else ""
    text = (f"{test['scenarios']} test runs, which no monitor trained or was calibrated on: "
            f"{test['violations']} with a collision, "
            f"{test['scenarios'] - test['violations']} collision-free{hours}")
    if val is not None:
        text += f"; the thresholds were set on {val['scenarios']} other, validation runs"
    return text


def describe(f: Figures) -> str:
    """One monitor's figures in a sentence."""
    if not f.reachable:
        return (f"{label(f.name)}: no threshold reaches the false-alarm budget on validation "
                "(n/r)")
    lead = ("" if f.lead["value"] is None
            else f", a median {with_ci(f.lead)} s before the collision")
    fa = f.false_alarms
    return (f"{label(f.name)} warned of {f.warned} of {f.collisions} collisions "
            f"({with_ci(f.recall, '%')} %){lead}; {with_ci(fa['per_h'])} false alarms per hour "
            f"of safe driving ({fa['alarmed_runs']} of {fa['safe_runs']} safe runs alarmed)")


def verdict(ours: Figures, rule: Figures) -> str:
    """Whether `ours` warns of more (or fewer) collisions than `rule`, on the same runs."""
    n = ours.collisions
    if _few(n):
        return (f"{n} test collision{'s' if n != 1 else ''}: too few to compare (at least "
                f"{MIN_COLLISIONS} needed); read the intervals")
    universe = sorted(ours.warned_ids | rule.warned_ids)
    p = paired_warnings_p([i in ours.warned_ids for i in universe],
                          [i in rule.warned_ids for i in universe])
    if p >= ALPHA:
        return (f"no clear difference in collisions warned of (paired test over the same "
                f"{n} collision runs: p = {p:.2f})" + _otherwise(ours, rule))
    word = "more" if ours.warned > rule.warned else "fewer"
    return (f"{label(ours.name)} warns of {word} collisions than {label(rule.name)} "
            f"(paired test over the same {n} collision runs: p = {p:.3f})")


def _otherwise(ours: Figures, rule: Figures) -> str:
    """Where two monitors that warn alike differ: false alarms per hour and the median lead,
    each only when their 95 % intervals lie apart (a conservative test)."""
    said = []
    ours_fa, rule_fa = ours.false_alarms["per_h"], rule.false_alarms["per_h"]
    fewer, more = _below(ours_fa, rule_fa), _below(rule_fa, ours_fa)
    if fewer or more:
        said.append(f"{label(ours.name)} raises {'fewer' if fewer else 'more'} false alarms per "
                    f"hour than {label(rule.name)} ({with_ci(ours_fa)} against "
                    f"{with_ci(rule_fa)})")
    earlier, later = _below(rule.lead, ours.lead), _below(ours.lead, rule.lead)
    if earlier or later:
        word = "earlier" if earlier else "later"
        said.append(f"{label(ours.name)} warns {word} (median lead {with_ci(ours.lead)} s "
                    f"against {with_ci(rule.lead)} s)")
    if not said:
        return ""
    return "; " + " and ".join(said) + ", their 95 % intervals apart"


def _below(a: dict, b: dict) -> bool:
    """Whether estimate `a`'s 95 % interval lies wholly below `b`'s (False without both)."""
    ia, ib = _interval(a), _interval(b)
    return ia is not None and ib is not None and ia[1] < ib[0]


def _interval(est: dict) -> tuple[float, float] | None:
    """An `Estimate.to_dict()`'s 95 % interval (no event: from 0); None without one."""
    if est["value"] is None:
        return None
    if est.get("method") == "poisson-zero":
        return 0.0, est["high"]
    if est.get("low") is None or est.get("high") is None:
        return None
    return est["low"], est["high"]


def scenario_words(name: str) -> str:
    """"highway-cut-in (S1: a highway, …)": a scenario's name and its label, if registered."""
    spec = SCENARIO_SPECS.get(name)
    return name if spec is None else f"{name} ({spec.label})"


def summary(report: dict) -> list[str]:
    """The plain-words headline of one logical scenario: a line per sentence."""
    point = operating_point(report)
    lines = [f"{scenario_words(report['logical_scenario'])} — {dataset_words(report, point)}."]
    ours, rule = trained(report, point), best_rule(report, point)
    lines += [f"  {describe(f)}." for f in ours]
    if rule is not None:
        lines.append(f"  Best rule-based baseline ({BEST_RULE}), {describe(rule)}.")
    if ours and rule is not None and ours[0].reachable and rule.reachable:
        lines.append(f"  Verdict: {verdict(ours[0], rule)}.")
    elif not ours and _few(report["dataset"]["test"]["violations"]):
        lines.append(f"  Caveat: {report['dataset']['test']['violations']} test collisions "
                     "are too few to compare monitors.")
    return lines


def point_note(reports: list[dict]) -> str:
    """The operating point of these reports, in words (the first report's)."""
    if not reports:
        return DASH
    return f"Operating point: {operating_point(reports[0]).words()}."
