"""The triggers a supervision compares, and the thresholds each is swept over.

A trigger is a monitor — a trained version (the FusionMonitor, by version) or a baseline by
name (TTC, TTC-2D, RSS, the AEM, the context-only control: `evaluation.monitors.BASELINES`) —
with thresholds calibrated on the scenario's validation frames, one per target false-positive
rate of the sweep (`calibrate`, the function every evaluation uses), from the paper's two
operating points down to the strictest the split resolves. Beyond it — above every validation
negative, where no FPR target reaches — the sweep goes on by the validation positives: one
threshold per target frame recall of `RECALLS` that still lies above the top negative, so a
trigger whose strictest FPR threshold still alarms too often on new runs has stricter ones to
offer. Targets that give the same threshold are one threshold. A worker loads the monitor again
from its `TriggerSpec` (picklable; kept per thread), so the sweep runs the same on local
processes or a task runner.

The *oracle* (`oracle_trigger`) is the ceiling every report draws beside them: it knows when
the unsupervised run collides and engages exactly τ s before, for each τ of `ORACLE_LEADS_S`,
and never in a run without a collision. Its score at a frame is minus the time left to the
collision, counted in whole frames (−inf in a safe run); its threshold for τ lies half a frame
beyond −τ, so it alarms first at the frame τ s before contact.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from evoeye.evaluation.baselines import rule_names
from evoeye.evaluation.dataset import load_split, narrow
from evoeye.evaluation.monitors import BASELINES, check_scores, monitor_context_len
from evoeye.monitor.calibration import calibrate
from evoeye.monitor.families import DEFAULT_FAMILY, FAMILIES, family_of, load_version
from evoeye.monitor.protocol import Monitor
from evoeye.paths import DataRoot
from evoeye.sim.runner import SimConfig
from evoeye.store import SplitSpec
from evoeye.store.windows import DEFAULT_HORIZON_S

# target FPRs on validation frames: the paper's 0.05 and 0.01, then stricter, to 1e-5 (below one
# false frame in the ≈ 80–150 k validation frames of a 1 000-run root)
SWEEP_FPRS = (0.05, 0.02, 0.01, 0.005, 0.002, 0.001, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5)
RECALLS = (0.2, 0.1, 0.05)  # target frame recalls on validation, above every negative
DEFAULT_BASELINES = ("ttc", "ttc-2d", "rss", "aem", "context-only")  # `evoeye supervise`'s
ORACLE = "oracle"  # the oracle trigger's name and source
ORACLE_LEADS_S = (0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5, 3.0)  # τ: it engages τ s before contact
FRAME_S = 1.0 / SimConfig().rate_hz  # the frames the oracle counts in (20 Hz)


@dataclass(frozen=True)
class TriggerSpec:
    """A trigger as a worker finds it again, and its thresholds (ascending, distinct)."""

    name: str  # the monitor's name: "fusion", "ttc", …; unique in a supervision
    source: str  # "version" (a trained version's id in `ref`) or "baseline" (a name in `ref`)
    ref: str
    version: str
    thresholds: tuple[float, ...]
    targets: tuple[str, ...]  # per threshold, the loosest target that gave it: "FPR 0.05", …
    val_fprs: tuple[float, ...]  # per threshold, the FPR it realises on validation
    val_recalls: tuple[float, ...]  # … and the frame recall
    scale: str = "score"  # what the thresholds compare: "score", or "logit" (`trigger_scores`)

    @property
    def label(self) -> str:
        """How reports name it: a family's label (FusionMonitor), with its version when a
        second version of the family is named by it (`trigger_names`), else its name."""
        if self.name == DEFAULT_FAMILY:
            return FAMILIES[DEFAULT_FAMILY].label
        if self.source == "version" and self.name == self.version:
            return f"{family_of(self.version).label} {self.version}"
        return self.name

    @property
    def rule_based(self) -> bool:
        return self.source == "baseline" and self.ref in rule_names()

    @property
    def oracle(self) -> bool:
        return self.source == ORACLE

    @property
    def leads_s(self) -> tuple[float, ...]:
        """The oracle's τ per threshold (its thresholds are −τ − half a frame)."""
        if not self.oracle:
            raise ValueError(f"{self.name} is no oracle: its thresholds are no leads")
        return tuple(round(-t - FRAME_S / 2, 6) for t in self.thresholds)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def of(cls, d: dict) -> TriggerSpec:
        return cls(**{**d, **{k: tuple(d[k]) for k in ("thresholds", "targets", "val_fprs",
                                                       "val_recalls")}})


def oracle_trigger(leads_s: Sequence[float] = ORACLE_LEADS_S) -> TriggerSpec:
    """The oracle (module doc), engaging τ s before each known collision for each τ."""
    if not leads_s or min(leads_s) <= 0:
        raise ValueError(f"the oracle's leads must be positive seconds, got {list(leads_s)}")
    leads = sorted({round(float(t), 6) for t in leads_s}, reverse=True)  # thresholds ascend
    n = len(leads)
    return TriggerSpec(ORACLE, ORACLE, "", "oracle-1",
                       tuple(-t - FRAME_S / 2 for t in leads), tuple(f"τ {t:g} s" for t in leads),
                       (0.0,) * n, (0.0,) * n)


def trigger_scores(monitor: Monitor, windows) -> tuple[np.ndarray, str]:
    """(scores, scale) a trigger thresholds: a monitor's logits where it has them (the
    FusionMonitor: its float32 risks saturate at 1.0, and a threshold there is "off"; the
    logits keep their order and stay apart), else its scores."""
    logits = getattr(monitor, "logits", None)
    if logits is not None:
        return logits(windows), "logit"
    return monitor.score(windows), "score"


def load_monitor(root: DataRoot, scenario: str, splits: SplitSpec, source: str,
                 ref: str) -> Monitor:
    """The monitor of a trigger: a saved version by id, or the named baseline (trained ones are
    found again by their training key, or trained)."""
    if source == "version":
        return load_version(root, ref)
    if source == "baseline":
        if ref not in BASELINES:
            raise KeyError(f"unknown baseline {ref!r}; known: {sorted(BASELINES)}")
        return BASELINES[ref](root, scenario, splits)
    raise ValueError(f"unknown trigger source {source!r}")


def sweep_thresholds(scores: np.ndarray, labels: np.ndarray, fprs: Sequence[float],
                     recalls: Sequence[float] = RECALLS) -> dict[float, str]:
    """Threshold → the loosest target giving it ("FPR α" of `fprs`, then "recall r" of
    `recalls` for those above every negative), ascending."""
    cal = calibrate(scores, labels, fprs)
    found: dict[float, str] = {}
    for fpr in sorted(cal.by_fpr, reverse=True):  # loosest first: it names its threshold
        found.setdefault(cal.by_fpr[fpr], f"FPR {fpr:g}")
    top_negative = float(np.max(scores[labels == 0]))
    positive = np.sort(scores[labels == 1])[::-1]  # descending
    for r in sorted(recalls, reverse=True):
        k = int(np.floor(r * len(positive)))  # k positives strictly above the k-th one
        if 0 < k < len(positive) and positive[k] > top_negative:
            found.setdefault(float(positive[k]), f"recall {r:g}")
    return dict(sorted(found.items()))


def realised(scores: np.ndarray, labels: np.ndarray, thresholds: Sequence[float]
             ) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(FPR, frame recall) each threshold realises on these scores (alarm: score > threshold)."""
    neg, pos = scores[labels == 0], scores[labels == 1]
    fpr = tuple(float((neg > t).mean()) if neg.size else 0.0 for t in thresholds)
    rec = tuple(float((pos > t).mean()) if pos.size else 0.0 for t in thresholds)
    return fpr, rec


def trigger_names(monitors: Sequence[Monitor]) -> list[str]:
    """Each monitor's trigger name: its own (fusion, ttc, …); a later version of a name already
    taken is named by its version id, so two FusionMonitors run side by side — the first keeps
    the name the headline and the paired differences compare from. ValueError for a monitor
    given twice."""
    names: list[str] = []
    for m in monitors:
        name = m.name if m.name not in names else m.version
        if name in names:
            raise ValueError(f"{name} is given twice as a trigger")
        names.append(name)
    return names


def calibrate_triggers(root: DataRoot, scenario: str,
                       sources: Sequence[tuple[str, str]],
                       splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
                       fprs: Sequence[float] = SWEEP_FPRS,
                       horizon_s: float = DEFAULT_HORIZON_S,
                       recalls: Sequence[float] = RECALLS) -> list[TriggerSpec]:
    """Each (source, ref) as a trigger with its sweep's thresholds, calibrated on the
    scenario's validation windows (each monitor at its own L)."""
    monitors = [load_monitor(root, scenario, splits, source, ref) for source, ref in sources]
    for m in monitors:
        trained = (getattr(m, "card", None) or {}).get("logical_scenario")
        if trained not in (None, scenario):
            raise ValueError(f"{m.version} was trained on {trained}, not {scenario}")
    names = trigger_names(monitors)
    L = max(monitor_context_len(m) for m in monitors)
    val = load_split(root, scenario, "val", splits, context_len=L, horizon_s=horizon_s)
    if len(val) == 0:
        raise ValueError(f"{scenario}: the validation split has no frames to calibrate on")
    specs = []
    for (source, ref), m, name in zip(sources, monitors, names, strict=True):
        raw, scale = trigger_scores(m, narrow(val.windows, monitor_context_len(m)))
        scores = check_scores(m, raw, len(val), unit_interval=scale == "score")
        labels = val.windows.label
        sweep = sweep_thresholds(scores, labels, fprs, recalls)
        fpr, recall = realised(scores, labels, list(sweep))
        specs.append(TriggerSpec(name, source, ref, m.version, tuple(sweep),
                                 tuple(sweep.values()), fpr, recall, scale))
    return specs
