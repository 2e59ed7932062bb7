"""Flow: train (or fine-tune) a FusionMonitor version on warehouse windows (a thin wrapper).

The task is not retried: training is deterministic, so a failure would repeat itself.
"""

from __future__ import annotations

from typing import Any

from prefect import flow, get_run_logger, task
from pydantic import BaseModel, Field, field_validator

from evoeye.evaluation.table import pct
from evoeye.monitor.inputs import parse_modules
from evoeye.monitor.recipes import COMMAND_RECIPE, recipe_params
from evoeye.paths import DataRoot
from evoeye.store import SplitSpec
from flows.published import named, publish, train_markdown


class TrainFlowParams(BaseModel):
    """What to train on and how; by default the scenario's train / val splits."""

    root: str | None = None  # default: $EVOEYE_HOME or ./evoeye-data
    scenario: str | None = "highway-cut-in"
    train_sql: str | None = None  # SQL returning scenario_id: overrides the train split
    val_sql: str | None = None  # … and the validation split
    context_len: int | None = Field(None, ge=1, le=64)  # None: the recipe's, or the parent's
    horizon_s: float = Field(3.0, gt=0.0)
    modules: str | None = None  # an ABLATIONS name or a comma list of MODULES; None: all
    seed: int = 0
    split_seed: int = 0
    recipe: str = COMMAND_RECIPE  # evoeye.monitor.recipes; the fields below override it
    epochs: int | None = Field(None, ge=1)  # None: the recipe's
    patience: int | None = Field(None, ge=1)
    batch_size: int | None = Field(None, ge=1)
    lr: float | None = Field(None, gt=0.0)
    init_from: str | None = None  # fine-tune this version

    @field_validator("modules")
    @classmethod
    def _known_modules(cls, value: str | None) -> str | None:
        parse_modules(value)  # raises ValueError naming the choices
        return value

    def run_name(self) -> str:
        start = f"from-{self.init_from}" if self.init_from else f"seed{self.seed}"
        return f"train-{self.scenario or 'sql'}-{start}"

    @field_validator("recipe")
    @classmethod
    def _known_recipe(cls, value: str) -> str:
        recipe_params(value)  # raises ValueError naming the choices
        return value


@task(task_run_name="train-{params.scenario}")
def train_version(params: TrainFlowParams, root: DataRoot) -> str:
    """One training run; the saved version's id."""
    from evoeye.monitor.train import train_monitor

    return train_monitor(
        root, params.scenario, context_len=params.context_len, horizon_s=params.horizon_s,
        modules=parse_modules(params.modules), seed=params.seed,
        splits=SplitSpec(seed=params.split_seed),
        train_runs=params.train_sql, val_runs=params.val_sql, init_from=params.init_from,
        recipe=params.recipe, **{k: v for k in ("epochs", "patience", "batch_size", "lr")
                                 if (v := getattr(params, k)) is not None},
    )


@flow(name="evoeye-train", log_prints=True,
      flow_run_name=named(lambda p: (p or TrainFlowParams()).run_name()))
def train_flow(params: TrainFlowParams | None = None) -> dict[str, Any]:
    """Train a monitor version; its id, card path and validation metrics."""
    from evoeye.monitor.registry import CARD_FILE, read_card, version_dir

    params = params or TrainFlowParams()
    root = DataRoot.resolve(params.root)
    version = train_version(params, root)
    card = read_card(root, version)
    val = card["metrics"]["val"]
    get_run_logger().info(
        "%s: val AUROC %s %%, AUPRC %s %%, F1@0.05 %s %% (best epoch %d, %.1f s)", version,
        pct(val["auroc"]), pct(val["auprc"]), pct(val["fpr_0.05"]["f1"]),
        card["training"]["best_epoch"], card["training"]["time_s"])
    publish("evoeye-train", train_markdown(version, card), str(version_dir(root, version)))
    return {"version": version, "card": str(version_dir(root, version) / CARD_FILE),
            "parent": card["parent"], "metrics": val, "thresholds": card["thresholds"]}


if __name__ == "__main__":
    from flows.command_line import run_from_command_line

    run_from_command_line(TrainFlowParams, train_flow, __doc__)
