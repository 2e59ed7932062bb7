"""`evoeye explain`: which module's oracle avoids each collision, and could a careful driver?"""

from __future__ import annotations

import time
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.errors import UserError
from evoeye.cli.output import out, table
from evoeye.cli.warehouse import RootOpt, attribution_table
from evoeye.paths import DataRoot

if TYPE_CHECKING:
    from rich.table import Table

    from evoeye.evaluation.explain import Explained



def _verdict(collided: bool) -> str:
    """✓: the variant avoids the collision; ✗: the ego still collides."""
    return "[red]✗[/]" if collided else "[green]✓[/]"


def runs_table(done: list[Explained]) -> Table:
    """One row per run: each oracle's verdict, the careful driver's, and the cause shares."""
    from evoeye.sim.counterfactual import ORACLES, avoided_by  # loaded by the explaining

    t = table("explain (✓ avoids the collision, ✗ still collides)",
              ["run", "t_col s", *(o.removeprefix("oracle_") for o in ORACLES),
               "careful (brakes at)", "cause share %"], left=("run", "cause share %"))
    for e in done:
        if e.explanation is None:
            t.add_row(e.spec.scenario_id, "", *[""] * len(ORACLES), "",
                      f"[yellow]not explained[/]: {e.error}")
            continue
        ex = e.explanation
        by = {v.variant: v for v in ex.variants}
        avoiding = avoided_by(ex.variants)
        careful = by["careful_driver"]
        react = f" @{careful.react_s:.2f} s" if careful.react_s is not None else ""
        behind = " (struck from behind)" if careful.struck_from_behind else ""
        causes = (" ".join(f"{c} {100 / len(avoiding):.0f}" for c in avoiding)
                  if avoiding else "compound 100")
        t.add_row(ex.spec.scenario_id, f"{ex.collision_time_s:.2f}",
                  *(_verdict(by[o].collided) for o in ORACLES),
                  _verdict(careful.collided) + react + behind, causes)
    return t


@app.command()
def explain(
    log: Annotated[Path | None, typer.Argument(
        help="Explain this one run log (its spec is read from the log's metadata; nothing is "
             "stored). Without it: every ingested collision run not yet explained.")] = None,
    root: RootOpt = None,
    scenario: Annotated[str | None, typer.Option(
        callback=scenario_check(recorded=True),
        help=scenario_help("Only this logical scenario.", recorded=True))] = None,
    batch: Annotated[str | None, typer.Option(help="Only this batch.")] = None,
    limit: Annotated[int | None, typer.Option(min=1, help="At most this many runs.")] = None,
    workers: Annotated[int, typer.Option(min=1, help="Worker processes.")] = 2,
) -> None:
    """Re-simulate collision runs with one module at a time replaced by an oracle, and with a
    careful reference driver; store the outcomes in the warehouse table `attribution`."""
    from evoeye.evaluation.explain import (
        attribution_shares,
        explain_one,
        explain_runs,
        pending_runs,
        spec_of,
    )
    from evoeye.log import LogError, read_run

    t0 = time.perf_counter()
    if log is not None:
        try:
            meta = read_run(log, topics=()).metadata
        except (LogError, OSError) as exc:
            raise UserError(str(exc), "give the path of a run's .mcap log") from exc
        if not meta["collided"]:
            out().print(f"{meta['scenario_id']}: no collision in this run, nothing to explain")
            return
        out().print(runs_table([explain_one(spec_of(meta))]))
        return
    data = DataRoot.existing(root)
    specs = pending_runs(data, scenario, batch, limit)
    if not specs:
        out().print("nothing to explain: every ingested collision run is explained "
                    "(or none is ingested: run `evoeye ingest`)")
        return
    out().print(f"explaining {len(specs)} collision runs with {workers} workers …")
    done = explain_runs(data, specs, workers=workers)  # a locked warehouse: a known user error
    out().print(runs_table(done))
    shares = attribution_shares(data, scenario)
    if shares:
        out().print(attribution_table(shares))
    sims = Counter((v.simulations, v.converged) for e in done if e.explanation
                   for v in e.explanation.variants if v.variant == "oracle_prediction")
    if sims:
        out().print("oracle prediction, re-simulations until the outcome repeated: " + ", ".join(
            f"{n}{'' if ok else ' (not repeated, cap)'}: {sims[n, ok]} runs"
            for n, ok in sorted(sims)))
    failed = sum(e.explanation is None for e in done)
    out().print(f"{len(done) - failed} runs explained, {failed} not, "
                f"in {time.perf_counter() - t0:.1f} s")

