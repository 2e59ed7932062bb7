"""`evoeye monitors`: the trained monitor versions of a data root, what each is and how good."""

from __future__ import annotations

import json
import sys
from typing import Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.output import out, table
from evoeye.cli.simulate import RootOpt
from evoeye.paths import DataRoot


def _pct(x: float | None) -> str:
    return "–" if x is None else f"{100 * x:.1f}"


def _count(x: int | None) -> str:
    return "–" if x is None else f"{x:,}"


@app.command("monitors")
def monitors_command(
    root: RootOpt = None,
    scenario: Annotated[str | None, typer.Option(
        "--scenario", callback=scenario_check(recorded=True), help=scenario_help(
            "Only the versions trained on this logical scenario.", recorded=True))] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the rows as JSON.")] = False,
) -> None:
    """List the trained monitors: version, scenario, family, parent, training data, validation
    figures (%; F1 at the threshold for target FPR 0.05) and the campaign rounds they are G_r
    of."""
    import evoeye.baselines  # noqa: F401  (registers the trained baselines' families)
    from evoeye.monitor.listing import list_monitors

    rows = list_monitors(DataRoot.existing(root), scenario)
    if as_json:
        sys.stdout.write(json.dumps([r.to_dict() for r in rows], indent=1) + "\n")
        return
    t = table(f"{len(rows)} monitor version(s)", [
        "version", "scenario", "family", "parent", "train runs", "train frames",
        "val AUROC %", "val AUPRC %", "val F1@0.05 %", "campaign round"],
        left=("version", "scenario", "family", "parent", "campaign round"))
    for r in rows:
        t.add_row(r.version, r.logical_scenario or "–", r.family, r.parent or "–",
                  _count(r.train_runs), _count(r.train_frames), _pct(r.val_auroc),
                  _pct(r.val_auprc), _pct(r.val_f1), ", ".join(r.rounds) or "–")
    out().print(t)
    if not rows:
        out().print("train one: `evoeye train --scenario NAME`, or run `evoeye demo`")
