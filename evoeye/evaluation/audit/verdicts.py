"""The audit's verdicts: each realism criterion against its threshold (docs/audit.md).

A verdict is passed / failed, or None when it cannot be judged yet (no ingested frames, no
explained runs); `--strict` fails on a failed verdict only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

from evoeye.evaluation.audit.attribution import MODULES
from evoeye.scenarios import SCENARIO_SPECS, AuditBands

if TYPE_CHECKING:
    from evoeye.evaluation.audit.summary import ScenarioAudit



def bands_of(scenario: str) -> AuditBands | None:
    """The scenario's audit bands (its `ScenarioSpec.bands`); None for one not registered."""
    spec = SCENARIO_SPECS.get(scenario)
    return None if spec is None else spec.bands


@dataclass(frozen=True)
class Thresholds:
    """The batch-level thresholds."""

    careful_avoidable_min: float = 0.80
    careful_unavoidable_max: float = 0.20
    # the clock-only and context-only controls' limits for a scenario not registered (a
    # registered one brings its own, `AuditBands`)
    clock_auroc_max: float = AuditBands.clock_auroc_max
    context_auroc_max: float = AuditBands.context_auroc_max
    diverse_modules_min: int = 3  # modules with at least module_share_min of the credit
    module_share_min: float = 0.10
    module_share_max: float = 0.60


@dataclass(frozen=True)
class Verdict:
    """One criterion: the measured value, the bound, and whether it holds (None: not judged)."""

    criterion: str
    value: str
    bound: str
    passed: bool | None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @property
    def mark(self) -> str:
        return {True: "PASS", False: "FAIL", None: "n/a"}[self.passed]


def _pct(x: float) -> str:
    return f"{100.0 * x:.1f} %"


NOT_EXPLAINED = "not explained yet — run `evoeye explain`"
NOT_INGESTED = "not ingested yet — run `evoeye ingest`"


def _collision_rate(s: ScenarioAudit, t: Thresholds) -> Verdict:
    bands = bands_of(s.logical_scenario)
    band = None if bands is None else bands.collision_rate
    value = f"{s.collided_runs}/{s.ok_runs} = {_pct(s.collision_rate)}" if s.ok_runs else "no runs"
    if band is None or not s.ok_runs:
        return Verdict("collision rate", value, "no band for this scenario", None)
    lo, hi = band
    return Verdict("collision rate", value, f"{_pct(lo)}–{_pct(hi)}",
                   lo <= s.collision_rate <= hi)


def _kinematics(s: ScenarioAudit, t: Thresholds) -> Verdict:
    return Verdict("kinematics (NPC before the ego's collision)",
                   f"{s.kinematic_runs} runs", "0 runs", s.kinematic_runs == 0)


def _pass_through(s: ScenarioAudit, t: Thresholds) -> Verdict:
    return Verdict("pass-through (NPC overlaps without contact)",
                   f"{s.pass_through_runs} runs", "0 runs", s.pass_through_runs == 0)


def _pop_in(s: ScenarioAudit, t: Thresholds) -> Verdict:
    return Verdict("pop-in (late actors near the ego)", f"{s.pop_in_actors} actors", "0 actors",
                   s.pop_in_actors == 0)


def _careful(s: ScenarioAudit, t: Thresholds) -> Verdict:
    bound = f"avoidable ≥ {_pct(t.careful_avoidable_min)}, unavoidable ≤ " \
            f"{_pct(t.careful_unavoidable_max)}"
    a = s.attribution
    if a is None or a.careful_avoidable is None:
        return Verdict("careful driver", NOT_EXPLAINED, bound, None)
    value = f"avoidable {_pct(a.careful_avoidable)}, unavoidable " \
            f"{_pct(a.careful_unavoidable)} of {a.careful_runs}"
    return Verdict("careful driver", value, bound,
                   a.careful_avoidable >= t.careful_avoidable_min
                   and a.careful_unavoidable <= t.careful_unavoidable_max)


def _controls(s: ScenarioAudit, t: Thresholds) -> tuple[float, float]:
    """The clock-only and context-only AUROC limits for the scenario."""
    bands = bands_of(s.logical_scenario)
    if bands is None:
        return t.clock_auroc_max, t.context_auroc_max
    return bands.clock_auroc_max, bands.context_auroc_max


def _clock(s: ScenarioAudit, t: Thresholds) -> Verdict:
    limit = _controls(s, t)[0]
    bound = f"≤ {limit:.2f}"
    if s.clock is None:
        return Verdict("clock-only AUROC", NOT_INGESTED, bound, None)
    h = s.clock.headline
    if h is None:
        return Verdict("clock-only AUROC", "undefined (one label class only)", bound, None)
    return Verdict("clock-only AUROC", f"{h:.3f}", bound, h <= limit)


def _context(s: ScenarioAudit, t: Thresholds) -> Verdict:
    limit = _controls(s, t)[1]
    name, bound = "context-only AUROC", f"≤ {limit:.2f} (room for RQ1's +5)"
    if s.context is None:
        return Verdict(name, NOT_INGESTED, bound, None)
    c = s.context
    if c.auroc is None:
        return Verdict(name, "undefined (one label class only)", bound, None)
    return Verdict(name, f"{c.auroc:.3f} (AUPRC {c.auprc:.3f})", bound,
                   c.auroc <= limit)


def _diverse(s: ScenarioAudit, t: Thresholds) -> Verdict:
    bound = f"≥ {t.diverse_modules_min} modules ≥ {_pct(t.module_share_min)}, none > " \
            f"{_pct(t.module_share_max)}"
    a = s.attribution
    if a is None:
        return Verdict("diverse causes", NOT_EXPLAINED, bound, None)
    shares = {m: a.credit_share[m] for m in MODULES}
    value = ", ".join(f"{m} {_pct(v)}" for m, v in shares.items()) + \
        f", compound {_pct(a.credit_share['compound'])}"
    big = sum(v >= t.module_share_min for v in shares.values())
    return Verdict("diverse causes", value, bound,
                   big >= t.diverse_modules_min and max(shares.values()) <= t.module_share_max)


VERDICTS: tuple[Callable[[ScenarioAudit, Thresholds], Verdict], ...] = (
    _collision_rate, _kinematics, _pass_through, _pop_in, _careful, _clock, _context,
    _diverse,
)


DEFAULT_THRESHOLDS = Thresholds()


def verdicts(s: ScenarioAudit, thresholds: Thresholds = DEFAULT_THRESHOLDS) -> list[Verdict]:
    """Every criterion of one logical scenario's audit."""
    return [judge(s, thresholds) for judge in VERDICTS]
