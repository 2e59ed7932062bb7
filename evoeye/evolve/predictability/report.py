"""The predictability report: `predictability.md` for people, `predictability.json` for scripts."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import orjson

from evoeye.evolve.predictability.metrics import FOLDS
from evoeye.paths import DataRoot


def report_dir(root: DataRoot, scenario: str | None, batch: str | None) -> Path:
    """reports/predictability-<scenario>-<batch>/ ("all" for what was not narrowed)."""
    return root.reports / f"predictability-{scenario or 'all'}-{batch or 'all'}"


def _num(x: float | None, digits: int = 2) -> str:
    return "–" if x is None else f"{x:.{digits}f}"


def _regressed(r: dict | None) -> str:
    if r is None or r["spearman"] is None:
        return "–"
    return (f"R² {_num(r['r2'])}, Spearman {_num(r['spearman'])} "
            f"(p {r['spearman_p']:.1g})")


def regime_markdown(r: dict[str, Any]) -> list[str]:
    """One regime's section."""
    c, m, mon, noise = r["collision"], r["margin"], r["monitor"], r["label_noise"]
    batch = f", batch `{r['batch']}`" if r["batch"] else ""
    out = [f"## {r['scenario']} (ADS profile `{r['ads_profile']}`){batch}: {r['runs']} runs, "
           f"{100 * r['collision_share']:.1f} % collide", "",
           f"| what θ alone predicts ({FOLDS}-fold CV, random forest) | runs | figure |",
           "|---|---|---|",
           f"| collision | {c['runs']} ({c['positives']} collide) | AUROC {_num(c['auroc'])} |",
           f"| signed safety margin (gap m; a collision −1 m) | {m['runs']} | {_regressed(m)} |"]
    if mon["version"]:
        err = mon["error"]
        out.append(f"| monitor error mean \\|ŷ − y\\| (`{mon['version']}`, {mon['feedback']}; "
                   f"runs it did not train on) | {mon['unseen_runs']} | {_regressed(err)} |")
    out.append("")
    if mon["note"]:
        out += [f"No monitor: {mon['note']}", ""]
    boundary = (r["boundary_noise"], "nearest the failure boundary (out-of-fold P(collision) "
                                     "nearest ½)")
    for flips, where in ((noise, "drawn uniformly"), boundary):
        if flips:
            out += [f"Label noise, {flips['thetas']} θ {where}, re-simulated with "
                    f"{flips['seeds']} new seeds each: {100 * flips['flip_share']:.1f} % of the "
                    f"re-simulations flip the outcome, {100 * flips['ambiguous_share']:.1f} % of "
                    f"θ are ambiguous, {100 * flips['collision_share']:.1f} % collide.", ""]
    return out + ["Verdict:", "", *(f"* {line}" for line in r["verdict"]), ""]


def markdown(regimes: list[dict[str, Any]], command: str) -> str:
    lines = ["# Is search worth it here? θ-predictability of outcome and monitor error", "",
             f"`{command}`", "",
             "A strategy that chooses θ can beat Uniform only where what it steers by is "
             "predictable from θ before the run. Each figure is a random forest's out-of-fold "
             "prediction from the normalised scenario parameters alone.", ""]
    for r in regimes:
        lines += regime_markdown(r)
    return "\n".join(lines)


def write_report(root: DataRoot, regimes: list[dict[str, Any]], scenario: str | None,
                 batch: str | None, command: str) -> Path:
    """Write the report's two files; its folder."""
    folder = report_dir(root, scenario, batch)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "predictability.json").write_bytes(orjson.dumps(
        {"command": command, "regimes": regimes},
        option=orjson.OPT_INDENT_2 | orjson.OPT_SERIALIZE_NUMPY))
    (folder / "predictability.md").write_text(markdown(regimes, command), encoding="utf-8")
    return folder
