"""The paper's monitor ablation (Table "monitor ablation"): context length L and module inputs.

Variants: L ∈ {1, 3, 5, 7} with every module input, and at L = 5 the inputs perception,
+ prediction, + planning (and all four: the full FusionMonitor, which is also the L = 5 row).
Each variant is a FusionMonitor trained by `evoeye.monitor.train_monitor` (seeded: the same
seed and data give the same version) and evaluated like RQ1; the table reports F1 at the first
target FPR, AUROC and AUPRC on the test frames per logical scenario. The last rows are
references, calibrated and evaluated the same way: the context-only control (clock, ego speed
and position; `evoeye.baselines.context`) — a variant that cannot clearly beat it has learned
the scenario script — and the rule baselines TTC, TTC-2D, RSS and RSS-2s.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

from evoeye.evaluation.harness import evaluate
from evoeye.evaluation.monitors import baseline_monitors, monitor_context_len, train_fusion
from evoeye.evaluation.report import DASH, UNREACHABLE, UNREACHABLE_NOTE, Table, pct, rate
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec

CONTEXT_LENS = (1, 3, 5, 7)
FULL_INPUTS = "all"
CONTROL = "context-only"  # the control row's label and baseline name
REFERENCES = (CONTROL, "where-when", "ttc", "ttc-2d", "rss",
              "rss-2s")  # baseline rows, by baseline name


def input_sets() -> dict[str, tuple[str, ...]]:
    """Name → modules of the input ablation, from the FusionMonitor's own list."""
    from evoeye.monitor.model import ABLATIONS

    return dict(ABLATIONS)


@dataclass(frozen=True)
class Variant:
    """One ablation row: a context length and the module inputs."""

    label: str
    context_len: int
    inputs: str  # a key of input_sets()


def variants(context_lens: Sequence[int] = CONTEXT_LENS,
             inputs: Sequence[str] | None = None) -> list[Variant]:
    """The L rows (all inputs) then the input rows at L = 5 (the full model once)."""
    out = [Variant(f"L={L}", L, FULL_INPUTS) for L in context_lens]
    names = list(input_sets()) if inputs is None else list(inputs)
    out += [Variant(n, 5, n) for n in names if n != FULL_INPUTS]
    if FULL_INPUTS in names and 5 not in context_lens:
        out.append(Variant(FULL_INPUTS, 5, FULL_INPUTS))
    return out


@dataclass
class AblationRow:
    label: str
    context_len: int
    inputs: str
    results: dict[str, dict] = field(default_factory=dict)  # scenario → f1/auroc/auprc/version


@dataclass
class AblationReport:
    scenarios: list[str]
    fpr: float
    seed: int
    rows: list[AblationRow]

    def to_dict(self) -> dict:
        return asdict(self)

    def table(self) -> Table:
        header = ["Variant"]
        for s in self.scenarios:
            header += [f"{s} F1@{self.fpr}", f"{s} AUROC", f"{s} AUPRC"]
        body: list[list[str]] = []
        for row in self.rows:
            cells = [row.label]
            for s in self.scenarios:
                r = row.results.get(s)
                cells += [rate(r, "f1"), pct(r["auroc"]), pct(r["auprc"])] if r else [DASH] * 3
            body.append(cells)
        return Table(header, body)

    def write(self, root: DataRoot, name: str = "ablation") -> Path:
        """Write ablation.md and ablation.json under `<root>/reports/<name>/`; the folder."""
        folder = root.path / "reports" / name
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "ablation.md").write_text(self.markdown(), encoding="utf-8")
        (folder / "ablation.json").write_text(json.dumps(self.to_dict(), indent=1) + "\n",
                                              encoding="utf-8")
        return folder

    def markdown(self) -> str:
        table = self.table()
        unreachable = any(UNREACHABLE in row for row in table.rows)
        return ("# Monitor ablation (test frames)\n\n"
                f"Rates in %; F1 at the threshold calibrated on validation for FPR {self.fpr}; "
                f"seed {self.seed}. L rows use every module input; input rows use L = 5; "
                f"{CONTROL} is the control that sees only the clock, the ego's speed and its "
                "position; ttc, ttc-2d, rss and rss-2s are the rule baselines.\n\n"
                + table.markdown() + "\n" + (f"\n{UNREACHABLE_NOTE}\n" if unreachable else ""))


def run_ablation(
    root: DataRoot,
    scenarios: Sequence[str],
    splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
    *,
    context_lens: Sequence[int] = CONTEXT_LENS,
    inputs: Sequence[str] | None = None,
    seed: int = 0,
    references: Sequence[str] = REFERENCES,
    store_scores: bool = True,
    progress: Callable[[str], None] | None = None,
    **train_overrides,
) -> AblationReport:
    """Train and evaluate every variant, then the `references` (baseline names), on every
    scenario; the ablation table's figures."""
    sets = input_sets()
    rows = [AblationRow(v.label, v.context_len, v.inputs) for v in variants(context_lens, inputs)]
    rows += [AblationRow(name, 1, name) for name in references]
    fprs = None
    for scenario in scenarios:
        for row in rows:
            if progress is not None:
                progress(f"{scenario}: {row.label}")
            if row.inputs in sets:
                monitor = train_fusion(root, scenario, context_len=row.context_len,
                                       modules=sets[row.inputs], seed=seed, splits=splits,
                                       **train_overrides)
            else:
                monitor = baseline_monitors(root, scenario, splits, [row.inputs])[0]
                row.context_len = monitor_context_len(monitor)
            rep = evaluate(root, [monitor], scenario, splits, ks=(), store_scores=store_scores)
            fprs = rep.fprs
            m = rep.monitors[0]
            at = m.frame.at_fpr[rep.fprs[0]]
            row.results[scenario] = {
                "f1": at.f1, "reachable": at.reachable, "auroc": m.frame.auroc,
                "auprc": m.frame.auprc, "version": m.version,
            }
    return AblationReport(list(scenarios), (fprs or (0.05,))[0], seed, rows)
