"""`evoeye train`, `evoeye replay` and `evoeye export`: the FusionMonitor from the shell."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from evoeye.cli.app import app
from evoeye.cli.choices import scenario_check, scenario_help
from evoeye.cli.defaults import ABLATION_NAMES as ABLATIONS
from evoeye.cli.defaults import COMMAND_RECIPE, RECIPE_NAMES, SPLIT_SEED, TARGET_FPRS, WARNING_K
from evoeye.cli.defaults import CONTEXT_LEN as DEFAULT_CONTEXT_LEN
from evoeye.cli.defaults import HORIZON_S as DEFAULT_HORIZON_S
from evoeye.cli.defaults import MODULE_NAMES as MODULES
from evoeye.cli.errors import UserError
from evoeye.cli.output import err, out, table
from evoeye.paths import DataRoot

if TYPE_CHECKING:
    from rich.table import Table

RootOpt = Annotated[
    Path | None,
    typer.Option("--root", help="Data root (default: $EVOEYE_HOME or ./evoeye-data)."),
]
MonitorOpt = Annotated[str, typer.Option("--monitor", help="Monitor version, e.g. fusion-…")]


def _pct(value: float | None) -> str:
    return "—" if value is None else f"{100 * value:.1f}"


def metrics_table(card: dict[str, Any]) -> Table:
    """Validation metrics of a card: AUROC, AUPRC and precision / recall / F1 per target FPR."""
    val = card["metrics"]["val"]
    t = table(f"{card['version']} on validation (%)",
              ["AUROC", "AUPRC", "target FPR", "threshold", "Prec.", "Rec.", "F1", "FPR"])
    for i, fpr in enumerate(sorted((float(f) for f in card["thresholds"]), reverse=True)):
        m = val[f"fpr_{fpr:g}"]
        # n/r: no threshold meets this target with any alarm (evoeye.monitor.calibration)
        rates = ([_pct(m[k]) for k in ("precision", "recall", "f1")]
                 if m.get("reachable", True) else ["n/r"] * 3)
        t.add_row(_pct(val["auroc"]) if i == 0 else "", _pct(val["auprc"]) if i == 0 else "",
                  f"{fpr:g}", f"{m['threshold']:.4f}", *rates, _pct(m["fpr"]))
    return t


@app.command("train")
def train_command(
    scenario: Annotated[str, typer.Option(
        "--scenario", callback=scenario_check(),
        help=scenario_help("Logical scenario to train on."))],
    root: RootOpt = None,
    context_len: Annotated[int | None, typer.Option(
        "--context-len", min=1, help=f"L, frames per context (default {DEFAULT_CONTEXT_LEN}, "
        "the lookahead recipes' own, or the parent's).")] = None,
    horizon_s: Annotated[float, typer.Option("--horizon-s", min=0.0,
                                             help="Label horizon H, s.")] = DEFAULT_HORIZON_S,
    modules: Annotated[str | None, typer.Option(
        "--modules", help=f"Inputs: one of {', '.join(ABLATIONS)} or a comma list of "
        f"{', '.join(MODULES)} (default: all).")] = None,
    seed: Annotated[int, typer.Option(help="Training seed.")] = 0,
    split_seed: Annotated[int, typer.Option(help="Seed of the train/val/test split.")] =
        SPLIT_SEED,
    recipe: Annotated[str, typer.Option(
        help=f"Training recipe, one of {', '.join(RECIPE_NAMES)}; the options below override "
             "its values (default: the monitor a supervisor's trigger needs, "
             "docs/lookahead.md).")] = COMMAND_RECIPE,
    epochs: Annotated[int | None, typer.Option(
        min=1, help="At most this many epochs (default: the recipe's).")] = None,
    patience: Annotated[int | None, typer.Option(
        min=1, help="Early-stopping patience (default: the recipe's).")] = None,
    batch_size: Annotated[int | None, typer.Option(
        min=1, help="Windows per step (default: the recipe's).")] = None,
    lr: Annotated[float | None, typer.Option(
        min=0.0, help="Adam's (peak) learning rate (default: the recipe's).")] = None,
    weight_decay: Annotated[float | None, typer.Option(
        min=0.0, help="Adam weight decay (default: the recipe's).")] = None,
    device: Annotated[str | None, typer.Option(
        help="cpu, cuda or cuda:N (default: $EVOEYE_DEVICE, else a GPU if there is one).")
    ] = None,
    dropout: Annotated[float | None, typer.Option(
        min=0.0, max=0.95, help="Dropout on frame features and the temporal MLP (default: "
        "none, or the parent's).")] = None,
    init_from: Annotated[str | None, typer.Option(
        "--init-from", help="Fine-tune this version instead of training from scratch.")] = None,
    keep_parent: Annotated[bool, typer.Option(
        "--keep-parent", help="With --init-from: keep the parent unless an epoch of the "
        "fine-tune beats it on the validation split.")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", help="No per-epoch lines.")] = False,
) -> None:
    """Train a FusionMonitor on the scenario's train split, calibrate it on val, save a version."""
    from evoeye.monitor.inputs import parse_modules
    from evoeye.monitor.registry import CARD_FILE, read_card, version_dir
    from evoeye.monitor.train import train_monitor
    from evoeye.store import SplitSpec

    if keep_parent and init_from is None:
        raise UserError("--keep-parent keeps the version a fine-tune starts from",
                        "give it with --init-from")
    data = DataRoot.existing(root)
    console = out()

    def progress(row: dict[str, Any]) -> None:
        if not quiet:
            console.print(f"epoch {row['epoch']:3d}  train loss {row['train_loss']:.4f}  "
                          f"val loss {row['val_loss']:.4f}  val AUROC {_pct(row['auroc'])}  "
                          f"val AUPRC {_pct(row['auprc'])}")

    given = {"epochs": epochs, "patience": patience, "batch_size": batch_size, "lr": lr,
             "weight_decay": weight_decay}
    try:
        version = train_monitor(
            data, scenario, context_len=context_len, horizon_s=horizon_s,
            modules=parse_modules(modules), dropout=dropout, seed=seed,
            splits=SplitSpec(seed=split_seed), init_from=init_from, progress=progress,
            recipe=recipe, device=device, keep_parent=keep_parent,
            **{k: v for k, v in given.items() if v is not None})
    except ValueError as exc:
        raise UserError(str(exc), ingested_words(data, scenario)) from exc
    if init_from is not None and version == init_from:
        console.print(f"no epoch of the fine-tune beat {init_from} on the validation split: "
                      "the parent is kept (its card below)")
    card = read_card(data, version)
    console.print(metrics_table(card))
    t = card["training"]
    console.print(f"recipe {card['recipe']}: best epoch {t['best_epoch']} of "
                  f"{t['epochs_run']}, {t['time_s']:.1f} s ({t['cpu_s']:.1f} s CPU) on "
                  f"{t['device']}, {card['n_parameters']:,} parameters, "
                  f"L = {card['context_len']}")
    console.print(f"card: {version_dir(data, version) / CARD_FILE}")
    console.print(f"version: [bold]{version}[/]")


RUN_COUNTS = ("SELECT logical_scenario, count(*) AS runs, count(*) FILTER (WHERE collided) AS "
              "collided FROM scenarios GROUP BY logical_scenario")


def ingested_words(data: DataRoot, scenario: str) -> str:
    """What the warehouse holds of `scenario`, as a hint under a failed training."""
    import duckdb

    from evoeye.store import Warehouse

    more = f"`evoeye simulate --scenario {scenario} --n N`, then `evoeye ingest`"
    try:
        rows = Warehouse(data).read_only_sql(RUN_COUNTS).to_pylist()
    except duckdb.Error:
        return f"the warehouse at {data.warehouse} cannot be read: {more}"
    row = next((r for r in rows if r["logical_scenario"] == scenario), None)
    if row is None:
        return f"no run of {scenario} is ingested: {more}"
    return (f"the warehouse holds {row['runs']} runs of {scenario}, {row['collided']} with a "
            f"collision; more runs: {more}")


@app.command("replay")
def replay_command(
    log: Annotated[Path, typer.Argument(help="Run log (.mcap) to replay.", exists=True,
                                        dir_okay=False)],
    monitor: MonitorOpt,
    root: RootOpt = None,
    output: Annotated[Path | None, typer.Option(
        "--out", help="Output log (default: <root>/replays/<log name>.<monitor>.risk.mcap, "
        "outside runs/ so that ingest never sees it).")] = None,
    fpr: Annotated[float, typer.Option(help=f"Alarm threshold's target FPR, one of "
                                       f"{TARGET_FPRS}.")] = TARGET_FPRS[0],
    consecutive: Annotated[int, typer.Option(
        "--consecutive", min=1, help="Frames above the threshold before the alarm (K; the "
        "reports' headline and the demo count a warning at the same K).")] = WARNING_K,
) -> None:
    """Copy a run log with the monitor's risk channel and alarm markers (Foxglove/Lichtblick).

    Warns when the monitor was trained on another logical scenario than the log's.
    """
    from evoeye.log import LogError, read_run
    from evoeye.monitor.registry import load_monitor
    from evoeye.monitor.replay import replay

    data = DataRoot.existing(root)
    fusion = load_monitor(data, monitor)
    try:
        logged = str(read_run(log, topics=()).metadata.get("logical_scenario"))
        if output is None:
            data.replays.mkdir(parents=True, exist_ok=True)
            output = data.replays / f"{log.stem}.{monitor}.risk.mcap"
        report = replay(log, fusion, output, fpr=fpr, consecutive=consecutive)
    except (LogError, ValueError, KeyError) as exc:
        raise UserError(str(exc), "give a run log (.mcap) written by `evoeye simulate`") from exc
    trained = fusion.card.get("logical_scenario")
    if trained and trained != logged:
        err().print(f"[yellow]warning:[/] {monitor} was trained on {trained}, the log is of "
                    f"{logged}: its risk there is not calibrated")
    out().print(f"{report.frames} frames, {report.alarm_frames} alarm frames (threshold "
                f"{report.threshold:.4f}, target FPR {fpr:g}, {consecutive} consecutive)")
    out().print(report.words())
    out().print(f"wrote {report.out}")


export_app = typer.Typer(
    invoke_without_command=True,
    help="Export a monitor version to ONNX (--monitor, --out), or runs to another stack's "
         "format (`evoeye export autoware`).")
app.add_typer(export_app, name="export")


@export_app.callback()
def export_command(
    ctx: typer.Context,
    monitor: Annotated[str | None, typer.Option("--monitor",
                                                help="Monitor version, e.g. fusion-…")] = None,
    output: Annotated[Path | None, typer.Option("--out", help="ONNX file to write.")] = None,
    root: RootOpt = None,
) -> None:
    """Export a monitor version to ONNX (dynamic batch axis; output: risk in [0, 1]); the
    file's metadata_props hold the version, the alarm thresholds and the input spec."""
    if ctx.invoked_subcommand is not None:
        return
    if monitor is None or output is None:
        raise UserError("`evoeye export` needs --monitor and --out (or a subcommand)",
                        "e.g. `evoeye export --monitor fusion-… --out monitor.onnx`")
    from evoeye.monitor.export import export_onnx
    from evoeye.monitor.registry import load_monitor

    path = export_onnx(load_monitor(DataRoot.existing(root), monitor), output)
    out().print(f"wrote {path}: inputs, thresholds and version in its metadata_props "
                "(evoeye.*)")
