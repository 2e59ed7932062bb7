"""`evoeye simulate`: a batch of uniformly sampled runs of one logical scenario, as MCAP logs."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from evoeye.cli.app import app, exit_with
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.defaults import ADS_PROFILE_NAMES, DEFAULT_LOCKSTEP, WORLD_NAMES
from evoeye.cli.errors import ExitCode, UserError
from evoeye.cli.output import err, out, table
from evoeye.paths import BadNameError, DataRoot, check_batch_name

if TYPE_CHECKING:
    from rich.table import Table

    from evoeye.batch import BatchSummary

RootOpt = Annotated[
    Path | None,
    typer.Option("--root", help="Data root (default: $EVOEYE_HOME or ./evoeye-data)."),
]


def plain_batch(name: str | None) -> str | None:
    """Typer callback: refuse a --batch that is not a plain name before anything runs."""
    try:
        return None if name is None else check_batch_name(name)
    except BadNameError as exc:
        raise typer.BadParameter(str(exc)) from None


BatchOpt = Annotated[str | None, typer.Option(
    callback=plain_batch, help="Batch name (default uniform-seed<S>): letters, digits, '.', '_', "
    "'-'.")]


def summary_table(title: str, rows: list[tuple[str, BatchSummary]]) -> Table:
    """One row per batch: runs, collisions, failures, skipped, simulated and wall time."""
    t = table(title, ["scenario", "runs", "collisions", "failures", "skipped", "sim s", "wall s",
                      "× rt"], left=("scenario",))
    for name, s in rows:
        done = s.runs - s.skipped
        share = f"{s.collisions} ({100.0 * s.collisions / max(1, s.runs):.0f} %)"
        rtf = f"{s.simulated_s / s.wall_s:.0f}" if done and s.wall_s > 0 else "-"
        t.add_row(name, str(s.runs), share, str(s.failures), str(s.skipped),
                  f"{s.simulated_s:.0f}", f"{s.wall_s:.1f}", rtf)
    return t


def known_profile(name: str) -> str:
    """Typer callback: refuse an unknown --ads before anything runs."""
    if name not in ADS_PROFILE_NAMES:
        raise typer.BadParameter(f"unknown ADS profile {name!r}; known: "
                                 f"{', '.join(ADS_PROFILE_NAMES)}")
    return name


AdsOpt = Annotated[str, typer.Option(
    "--ads", callback=known_profile, help=f"ADS profile that drives the ego: "
    f"{', '.join(ADS_PROFILE_NAMES)} (docs/world.md). A non-default profile's runs get ids, and "
    "a default batch name, of their own.")]


def known_world(name: str) -> str:
    """Typer callback: refuse an unknown --world before anything runs."""
    if name not in WORLD_NAMES:
        raise typer.BadParameter(f"unknown world {name!r}; known: {', '.join(WORLD_NAMES)}")
    return name


WorldOpt = Annotated[str, typer.Option(
    "--world", callback=known_world, help=f"World variant: {', '.join(WORLD_NAMES)} "
    "(docs/world.md; follower: a car behind the ego in its lane, highway-cut-in). A variant's "
    "runs get ids, and a default batch name, of their own; `evoeye ingest` leaves them out.")]


LockstepOpt = Annotated[int, typer.Option(
    "--lockstep", min=1, help="Runs stepped together by the lockstep engine (the same logs, "
    "byte for byte, at about half the CPU time per run; docs/world.md). 1: one run at a time.")]


SimulatedOpt = Annotated[str, typer.Option(
    "--scenario", callback=scenario_check(), help=scenario_help("Logical scenario."))]


def simulate_batch(scenario: str, n: int, seed: int, data: DataRoot, workers: int,
                   batch: str | None = None, ads: str = "default",
                   world: str = "default", lockstep: int = DEFAULT_LOCKSTEP) -> BatchSummary:
    """Plan, check the root can be written (PermissionError & co. if not), run with a progress
    bar, and report failures by scenario id."""
    from tqdm import tqdm

    from evoeye.batch import plan_uniform, run_batch

    try:
        specs = plan_uniform(scenario, n, seed, batch=batch, ads=ads, world=world)
    except ValueError as exc:  # includes ScenarioError and BadNameError
        raise UserError(str(exc), "see `evoeye simulate --help`") from exc
    data.runs.mkdir(parents=True, exist_ok=True)
    bar = lambda it: tqdm(it, total=len(specs), desc=scenario, unit="run")  # noqa: E731
    summary = run_batch(specs, data, workers=workers, progress=bar, lockstep=lockstep)
    for path in summary.stale_removed:
        out().print(f"[dim]removed the unfinished log of a killed run: {path}[/]")
    for r in summary.results:
        if r.status != "ok":
            out().print(f"[yellow]{r.status}[/] {r.scenario_id}: {r.reason}")
    return summary


def failures_code(rows: list[tuple[str, BatchSummary]]) -> ExitCode:
    """PARTIAL (and a line saying how many) if any run failed, else OK."""
    failed = sum(s.failures for _, s in rows)
    if not failed:
        return ExitCode.OK
    total = sum(s.runs for _, s in rows)
    err().print(f"[red]{failed} of {total} runs failed[/] (their reasons are "
                               "above); exit code 3")
    return ExitCode.PARTIAL


@app.command()
def simulate(
    scenario: SimulatedOpt,
    n: Annotated[int, typer.Option("--n", min=1, help="Number of runs.")] = 10,
    seed: Annotated[int, typer.Option(min=0, help="Batch seed: fixes vectors and run seeds.")] = 0,
    root: RootOpt = None,
    workers: Annotated[int, typer.Option(min=1, help="Worker processes.")] = 1,
    batch: BatchOpt = None,
    ads: AdsOpt = "default",
    world: WorldOpt = "default",
    lockstep: LockstepOpt = DEFAULT_LOCKSTEP,
) -> None:
    """Simulate N uniformly sampled concrete scenarios and write one MCAP log per run.

    Exits 3 if any run failed (the table and the lines above say which and why).
    """
    data = DataRoot.resolve(root)
    summary = simulate_batch(scenario, n, seed, data, workers, batch, ads, world, lockstep)
    out().print(summary_table("simulate", [(scenario, summary)]))
    out().print(f"logs: {data.runs / scenario}")
    exit_with(failures_code([(scenario, summary)]))
