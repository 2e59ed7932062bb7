"""Every table of docs/results, with its uncertainty, from the per-seed figures.

A table is a registered `TableSpec`: which part of the results it reads, which sets and metrics
it shows, its rows and the comparisons it makes. Its cells come from `evoeye.evaluation.stats`
alone: per row the mean over seeds with its Student-t 95 % CI (`mean_ci`), per comparison the
mean paired difference a − b with its BCa bootstrap 95 % CI and the Wilcoxon signed-rank p
(`compare_paired`, pairs by seed: training seeds in RQ1 and the monitor ablation, campaign seeds
in RQ2), plus the seed pairs a 5-point difference would need at 80 % power given the SDs and
pair correlation measured (`pairs_needed`). A seed whose figure is undefined — an unreachable
target FPR (F1 None), or a set without unsafe frames — is left out of its row's mean and of its
pairs, and counted (unreachable ones apart). Rows marked
unpaired (G_0's recipe over k training seeds, in RQ2) have a mean and CI but no comparison.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from evoeye.evaluation.stats import compare_paired, mean_ci, pairs_needed
from evoeye.evolve.campaign.assess import reached
from evoeye.results.rq1 import FUSION_LABEL
from evoeye.results.rq2 import G0, G0_SEEDS, g0_label

RQ2_SETS = ("test", "hard", "robust")
METRICS = ("f1@0.05", "f1@0.01", "auroc", "auprc")
ABLATION_METRICS = ("f1@0.05", "auroc", "auprc")  # the paper's ablation tables
EFFECT = 0.05  # a difference worth detecting: 5 points (of F1, on 0 … 1)
POWER = 0.8
SET_NAMES = {"test": "Test", "hard": "Hard", "robust": "Robust Hard", "acquired": "Acquired"}
FULL_VARIANTS = ("L=5", "all")  # the full FusionMonitor's label in the ablation


@dataclass(frozen=True)
class TableSpec:
    """One table: a part of the results, its sets, metrics, rows and comparisons (a − b)."""

    id: str
    part: str  # key of the results per scenario: rq1, ablation, rq2
    title: str
    sets: tuple[str, ...]
    metrics: tuple[str, ...]
    rows: Callable[[list[str]], list[str]]  # the part's methods → this table's rows, in order
    comparisons: Callable[[list[str]], list[tuple[str, str]]]  # its rows → pairs (a, b)
    over: str  # what the seeds are
    figures: Callable[[dict], list[dict]] = lambda row: row["figures"]  # per seed {set: metrics}


def _acquired(row: dict) -> list[dict]:
    """A campaign method's acquisition per seed as figures of the set "acquired" (a campaign
    that acquired nothing has none; results from before it was recorded, no row)."""
    return [{ACQUIRED: {k: a.get(k) for k in ACQUISITION_METRICS} if a else {}}
            for a in row.get("acquisition", [])]


def _in(order: tuple[str, ...]) -> Callable[[list[str]], list[str]]:
    return lambda have: [m for m in order if m in have]


def _against(reference: Callable[[list[str]], str | None]
             ) -> Callable[[list[str]], list[tuple[str, str]]]:
    def pairs(rows: list[str]) -> list[tuple[str, str]]:
        ref = reference(rows)
        return [(ref, m) for m in rows if ref is not None and m != ref]
    return pairs


def _evolution(winner: str, others: tuple[str, ...]) -> Callable[[list[str]], list[tuple]]:
    """winner − each other method, then every campaign method − its start G_0."""
    def pairs(rows: list[str]) -> list[tuple[str, str]]:
        runs = [m for m in rows if G0 not in m]
        out = [(winner, m) for m in others if winner in rows and m in rows]
        starts = [m for m in rows if G0 in m and not m.endswith("(k seeds)")]
        return out + [(m, starts[0]) for m in runs if starts]
    return pairs


RQ2_MAIN = ("uniform", "avfuzzer", "evoeye")
EVOLUTION_ABLATION = ("evoeye", "no-feedback", "no-density")
ACQUIRED = "acquired"
# what a campaign acquired (`evoeye.evolve.campaign.experiment`): the share of runs that
# collided, the share within δ of an earlier record (local mutations, in effect), and the mean
# feedback of its runs under the monitor that chose them (how wrong it was where it looked)
ACQUISITION_METRICS = ("collision_share", "near_share", "feedback")

TABLES: tuple[TableSpec, ...] = (
    TableSpec("rq1", "rq1", "Monitoring effectiveness, test frames (RQ1)", ("test",), METRICS,
              lambda have: list(have), _against(lambda rows: FUSION_LABEL), "training seeds"),
    TableSpec("ablation", "ablation", "Monitor ablation (test frames)", ("test",),
              ABLATION_METRICS, lambda have: list(have),
              _against(lambda rows: next((v for v in FULL_VARIANTS if v in rows), None)),
              "training seeds"),
    TableSpec("rq2", "rq2", "Self-evolution under the same budget (RQ2)", RQ2_SETS, METRICS,
              _in((G0, G0_SEEDS, *RQ2_MAIN)), _evolution("evoeye", ("uniform", "avfuzzer")),
              "campaign seeds"),
    TableSpec("evolution-ablation", "rq2", "Evolution ablation", RQ2_SETS, METRICS,
              _in((G0, G0_SEEDS, *EVOLUTION_ABLATION)),
              _evolution("evoeye", ("no-feedback", "no-density")), "campaign seeds"),
    TableSpec("acquisition", "rq2", "What each method acquired", (ACQUIRED,),
              ACQUISITION_METRICS, _in((*RQ2_MAIN, *EVOLUTION_ABLATION[1:], "aem-evo")),
              _evolution("evoeye", (*RQ2_MAIN[:2], *EVOLUTION_ABLATION[1:])), "campaign seeds",
              figures=_acquired),
    TableSpec("aem-evo", "rq2", "AEM-Evo", RQ2_SETS, METRICS,
              _in((g0_label("aem"), g0_label("aem", seeds=True), "aem-evo")),
              _evolution("aem-evo", ()), "campaign seeds"),
)


def cell_key(set_name: str, metric: str) -> str:
    return f"{set_name}/{metric}"


def values(figures: list[dict], set_name: str, metric: str) -> np.ndarray:
    """A row's figure per seed (NaN where undefined)."""
    return np.array([np.nan if f[set_name].get(metric) is None else float(f[set_name][metric])
                     for f in figures], dtype=float)


def unreachable(figures: list[dict], set_name: str, metric: str) -> int:
    """Seeds of a row whose figure is undefined because its target FPR was unreachable."""
    return sum(1 for f in figures if not reached(f[set_name], metric))


def _row_cell(figures: list[dict], set_name: str, metric: str) -> dict:
    v = values(figures, set_name, metric)
    n_r = unreachable(figures, set_name, metric)
    return {**mean_ci(v).to_dict(), "unreachable": n_r, "undefined": int(np.isnan(v).sum()) - n_r}


def _comparison_cell(a: np.ndarray, b: np.ndarray) -> dict:
    c = compare_paired(a, b)
    needed = None
    if c.sd_a is not None and c.sd_b is not None:
        # ρ is undefined only where one side does not vary (a rule, G_0): then it plays no part
        rho = 0.0 if c.correlation is None else c.correlation
        try:
            needed = pairs_needed(EFFECT, c.sd_a, c.sd_b, rho, power=POWER)
        except ValueError:  # more pairs than any design would run
            needed = None
    return {**c.to_dict(), "undefined": int((np.isnan(a) | np.isnan(b)).sum()),
            "pairs_needed": needed}


def build_table(spec: TableSpec, scenario: str, part: dict) -> dict | None:
    """A table's rows and comparisons for one scenario (None if none of its rows ran)."""
    methods = part["methods"]
    figures = {m: spec.figures(methods[m]) for m in spec.rows(list(methods))}
    rows = [m for m, f in figures.items() if f]
    if not any(not methods[m].get("unpaired") for m in rows):
        return None
    out_rows = [{"method": m, "n": len(figures[m]),
                 "unpaired": bool(methods[m].get("unpaired")),
                 "cells": {cell_key(s, k): _row_cell(figures[m], s, k)
                           for s in spec.sets for k in spec.metrics}} for m in rows]
    paired = [m for m in rows if not methods[m].get("unpaired")]
    comparisons = [{"a": a, "b": b,
                    "cells": {cell_key(s, k): _comparison_cell(values(figures[a], s, k),
                                                               values(figures[b], s, k))
                              for s in spec.sets for k in spec.metrics}}
                   for a, b in spec.comparisons(paired)]
    return {"id": spec.id, "scenario": scenario, "title": spec.title, "over": spec.over,
            "seeds": part.get("seeds", part.get("campaign_seeds")), "sets": list(spec.sets),
            "metrics": list(spec.metrics), "rows": out_rows, "comparisons": comparisons}


def build_tables(scenarios: dict) -> list[dict]:
    """Every registered table of every scenario that has its part."""
    out = []
    for spec in TABLES:
        for scenario, parts in scenarios.items():
            if spec.part in parts and (table := build_table(spec, scenario, parts[spec.part])):
                out.append(table)
    return out
