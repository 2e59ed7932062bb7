"""`evoeye supervise`: a batch re-simulated with each monitor as a safety supervisor's trigger."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.app import app, exit_with
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.defaults import (
    DEFAULT_FALLBACK,
    FALLBACKS,
    HORIZON_S,
    LOG_POLICIES,
    ORACLE_LEADS_S,
    SPLIT_SEED,
    SUPERVISE_BASELINES,
    SUPERVISE_BUDGETS,
    SWEEP_FPRS,
    SWEEP_RECALLS,
)
from evoeye.cli.errors import ExitCode, UserError
from evoeye.cli.evaluate import parse_baselines
from evoeye.cli.output import err, out, table
from evoeye.cli.simulate import RootOpt, plain_batch
from evoeye.paths import DataRoot


def parse_floats(text: str, what: str) -> tuple[float, ...]:
    """'0.05,0.01' → (0.05, 0.01); a clear error naming `what` otherwise."""
    try:
        values = tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise typer.BadParameter(f"{what}: give comma-separated numbers, got {text!r}") from None
    if not values or min(values) <= 0:
        raise typer.BadParameter(f"{what}: give positive numbers, got {text!r}")
    return values


def default_monitors(root: DataRoot, scenario: str, given: list[str] | None) -> list[str]:
    """The --monitor versions: as given ('none': none), else the newest FusionMonitor trained on
    the scenario (a campaign's G_0, `initial_monitor`), said on stderr; none without one."""
    if given:
        return [] if given == ["none"] else list(given)
    from evoeye.monitor.families import NoMonitorError, initial_monitor

    try:
        version = initial_monitor(root, scenario)
    except NoMonitorError:
        err().print(f"no FusionMonitor is trained on {scenario}: the triggers are baselines "
                    f"only (train one: `evoeye train --scenario {scenario}`)")
        return []
    err().print(f"monitor {version}: the newest FusionMonitor trained on {scenario} "
                "(--monitor to choose)")
    return [version]


@app.command("supervise")
def supervise_command(
    scenario: Annotated[str, typer.Option(
        callback=scenario_check(), help=scenario_help("Logical scenario."))],
    batch: Annotated[str, typer.Option(
        callback=plain_batch, help="The batch of logged runs to supervise (e.g. the Test Set's "
        "test-seed<S>): the same scenarios and seeds, paired.")],
    root: RootOpt = None,
    monitor: Annotated[list[str] | None, typer.Option(
        "--monitor", help="A trained monitor version as a trigger (repeatable: the first "
        "FusionMonitor is the one the headline compares; a second is named by its version; "
        "'none' for none). Default: the newest FusionMonitor trained on the scenario's train "
        "split, as a campaign's G_0.")] = None,
    baselines: Annotated[str, typer.Option(
        help="Comma-separated baselines as triggers ('none' for none).")] =
        ",".join(SUPERVISE_BASELINES),
    fprs: Annotated[str, typer.Option(
        help="Target FPRs on validation frames the thresholds are calibrated for.")] =
        ",".join(f"{f:g}" for f in SWEEP_FPRS),
    recalls: Annotated[str, typer.Option(
        help="Beyond them, target frame recalls on validation for thresholds above every "
        "validation negative ('none' for none).")] = ",".join(f"{r:g}" for r in SWEEP_RECALLS),
    consecutive: Annotated[int, typer.Option(min=1, help="K: frames above the threshold "
                                             "that raise the alarm.")] = 1,
    fallback: Annotated[str, typer.Option(
        help="The fallback: " + "; ".join(f"{n}: {f['decel_mps2']:g} m/s² at {f['jerk_mps3']:g} "
                                          "m/s³" for n, f in FALLBACKS.items())
        + ". The options below change one of its values.")] = DEFAULT_FALLBACK,
    decel_mps2: Annotated[float | None, typer.Option(
        help="Fallback deceleration, m/s² (at most 9, the tyres').", show_default="--fallback's")
        ] = None,
    jerk_mps3: Annotated[float | None, typer.Option(
        help="Fallback jerk limit, m/s³.", show_default="--fallback's")] = None,
    onset_s: Annotated[float | None, typer.Option(
        help="Brake dead time before the ramp, s.", show_default="--fallback's")] = None,
    hold_s: Annotated[float | None, typer.Option(
        help="The fallback ends once the score stays at or below the threshold this long, s.",
        show_default="--fallback's")] = None,
    stage_decel_mps2: Annotated[float | None, typer.Option(
        help="Staged braking: the ramp stops at this deceleration first, m/s² …",
        show_default="none")] = None,
    stage_s: Annotated[float | None, typer.Option(
        help="… for this long from its start, s.", show_default="none")] = None,
    horizon_s: Annotated[float, typer.Option(min=0.0, help="H: an intervention is true if the "
                                             "unsupervised run collides within it.")] = HORIZON_S,
    split_seed: Annotated[int, typer.Option(help="Split seed (calibration and the trained "
                                            "baselines).")] = SPLIT_SEED,
    train_frac: Annotated[float, typer.Option(help="Train share of the other round-0 runs.")] =
        0.8,
    val_frac: Annotated[float, typer.Option(help="Validation share of them.")] = 0.2,
    test_batch: Annotated[str | None, typer.Option(
        callback=plain_batch, help="The held-out Test Set batch (default: --batch).")] = None,
    logs: Annotated[str, typer.Option(help=f"Which supervised runs to log: "
                                      f"{', '.join(LOG_POLICIES)}.")] = "collided",
    logs_into_runs: Annotated[bool, typer.Option(
        "--logs-into-runs", help="Write the supervised runs' logs to runs/<scenario>/<batch>"
        "-supervised/ (ids of their own), so the next `evoeye ingest` takes them in as "
        "training data; by default they stay out of the warehouse.")] = False,
    budgets: Annotated[str, typer.Option(help="False interventions per hour the triggers are "
                                         "compared at.")] =
        ",".join(f"{b:g}" for b in SUPERVISE_BUDGETS),
    select_batch: Annotated[str | None, typer.Option(
        callback=plain_batch, help="A batch of other held-out runs, supervised too, on which "
        "each trigger's operating point at a budget is chosen (validation runs); without it "
        "the point is chosen on --batch itself and the report says so.")] = None,
    oracle_leads: Annotated[str, typer.Option(
        help="The oracle's leads τ, s: it engages τ s before each known collision, the ceiling "
        "every report draws ('none' for none).")] = ",".join(f"{t:g}" for t in ORACLE_LEADS_S),
    workers: Annotated[int, typer.Option(min=1, help="Worker processes.")] = 1,
    limit: Annotated[int | None, typer.Option(min=1, help="Only the batch's first N runs.")] =
        None,
    skip: Annotated[int, typer.Option(
        min=0, help="Report on --batch's runs after its first N (with --limit: runs N+1 … "
        "limit): a confirmation on runs an earlier look has not seen. The selection batch "
        "keeps its first --limit runs.")] = 0,
    name: Annotated[str | None, typer.Option(
        help="Report folder name under <root>/reports (default supervision-<UTC time>).")] =
        None,
    docs: Annotated[Path | None, typer.Option(
        help="Also write supervision-<scenario>.md/.svg/.json here (e.g. docs/results).")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the figures as one JSON "
                                          "object (its `rows`: per trigger and threshold).")] =
        False,
) -> None:
    """Re-simulate a batch with each trigger's supervisor: the monitor beside the ADS, a
    minimal-risk fallback on its alarm. Per trigger and threshold: collisions prevented and
    caused, false interventions per hour of safe driving, and what the fallback costs; the
    operating curves with paired bootstrap CIs. Resumes a killed run; exits 3 if a run failed.
    """
    from tqdm import tqdm

    from evoeye.evaluation.supervision import supervise
    from evoeye.evaluation.supervision.report import write_docs, write_report
    from evoeye.evaluation.supervision.summary import summarise_supervision
    from evoeye.sim.supervisor import fallback_with
    from evoeye.store import SplitSpec

    if logs not in LOG_POLICIES:
        raise typer.BadParameter(f"--logs: one of {', '.join(LOG_POLICIES)}, got {logs!r}")
    data = DataRoot.existing(root)
    sources = [("version", v) for v in default_monitors(data, scenario, monitor)]
    sources += [("baseline", b) for b in parse_baselines(baselines)]
    if not sources:
        raise typer.BadParameter("no trigger: give --monitor or --baselines")
    try:
        splits = SplitSpec(split_seed, train_frac, val_frac, test_batch or batch)
        fallback_config = fallback_with(fallback, decel_mps2=decel_mps2, jerk_mps3=jerk_mps3,
                                        onset_s=onset_s, hold_s=hold_s,
                                        stage_decel_mps2=stage_decel_mps2, stage_s=stage_s)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from exc
    bar = lambda it: tqdm(it, desc=f"supervise {scenario}", unit="run")  # noqa: E731
    try:
        result = supervise(data, scenario, batch, sources, splits=splits,
                           fprs=parse_floats(fprs, "--fprs"),
                           recalls=() if recalls == "none" else parse_floats(recalls, "--recalls"),
                           fallback=fallback_config,
                           consecutive=consecutive, horizon_s=horizon_s, logs=logs,
                           logs_into_runs=logs_into_runs, workers=workers, limit=limit,
                           skip=skip, progress=bar, select_batch=select_batch,
                           oracle_leads_s=() if oracle_leads == "none"
                           else parse_floats(oracle_leads, "--oracle-leads"))
        errors = result.errors + (result.select.errors if result.select else [])
        for sid, reason in errors:
            err().print(f"[yellow]error[/] {sid}: {reason}")
        summary = summarise_supervision(result.settings, result.records,
                                        parse_floats(budgets, "--budgets"),
                                        select=result.select.records if result.select else None)
    except (ValueError, KeyError) as exc:
        raise UserError(str(exc).strip("'\""), "check --scenario, --batch, --monitor and the "
                        "split options, and that `evoeye ingest` has run") from exc
    summary["folder"] = str(result.folder)
    summary["skipped_runs"] = skip
    summary["errors"] = [{"scenario_id": s, "reason": r} for s, r in errors]
    files = write_report(data, [summary], name)
    written = write_docs(docs, summary) if docs else []
    if as_json:
        sys.stdout.write(json.dumps(summary) + "\n")
    else:
        _print_summary(summary, result.done_before)
        for path in [files.html, *written]:
            out().print(f"report: {path}")
    exit_with(ExitCode.PARTIAL if errors else ExitCode.OK)


def _print_summary(summary: dict, done_before: int) -> None:
    from evoeye.evaluation.supervision.report import (
        budget_table,
        chosen_on,
        headline,
        headline_budget,
    )

    budget = headline_budget(summary)
    rows = budget_table(summary, budget)  # the report's own table at the headline budget
    t = table(f"supervise {summary['scenario']}: at ≤ {budget:g} false intervention/h",
              rows.header, left=(rows.header[0],))
    for row in rows.rows:
        t.add_row(*row)
    out().print(t)
    out().print(headline(summary, budget).replace("**", ""))
    out().print(chosen_on(summary))
    sims = summary["simulations"]
    out().print(f"{summary['runs']} runs ({done_before} done before), {sims['shared']} "
                f"simulations (every threshold alone: {sims['naive']}); results in "
                f"{summary['folder']}")
