"""The monitor families a campaign can evolve: the FusionMonitor, and the AEM baseline (AEM-Evo).

A family is a trainer with `train_monitor`'s signature (root, scenario, train_runs=, val_runs=,
seed=, init_from=, …) → version, and versions the loop can load: anything with `score(windows)`,
`thresholds`, `context_len`, `name` and `version`. FusionMonitor versions live in the monitor
registry; AEM versions under `<root>/baselines/aem/<version>/` (the RQ1 baseline's folder), with
the thresholds calibrated on the validation runs and the training selection in `meta.json`.

AEM-Evo (paper RQ3) runs Algorithm 1 unchanged with the AEM as the monitor: its reconstruction
risk is ŷ in f_r, it is fine-tuned (or retrained) on the collision-free windows of D_r every
round, and it is judged on the same Test Set and the FusionMonitor G_0's Hard Set. Its G_0 is
the AEM trained on D_init by the same recipe, found again by its training key.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from evoeye.paths import DataRoot
from evoeye.store import SplitSpec
from evoeye.store.selection import Runs
from evoeye.store.windows import DEFAULT_CONTEXT_LEN, DEFAULT_HORIZON_S

FAMILIES = ("fusion", "aem")


class NoMonitorError(LookupError):
    """A campaign needs a G_0 and none was named or trained for its scenario."""


class NoInitialDataError(LookupError):
    """A campaign needs the scenario's initial (round 0) runs in the warehouse."""


def family_of(version: str) -> str:
    return "aem" if version.startswith("aem-") else "fusion"


def load_version(root: DataRoot, version: str):
    """A version of either family, ready for batch scoring (FusionMonitors untraced: tracing
    pays off only over many calls)."""
    if family_of(version) == "aem":
        return load_aem_version(root, version)
    from evoeye.monitor import FusionMonitor, load_monitor

    m = load_monitor(root, version)
    return FusionMonitor(m.net, m.version, m.thresholds, m.card, trace=False)


@dataclass
class AEMVersion:
    """A saved AEM with the thresholds calibrated when it was trained."""

    aem: Any  # evoeye.baselines.aem.AEMMonitor
    thresholds: Any  # evoeye.monitor.protocol.Thresholds
    card: dict
    name: str = "aem"

    @property
    def version(self) -> str:
        return self.aem.version

    @property
    def context_len(self) -> int:
        return self.aem.context_len

    def score(self, windows) -> np.ndarray:
        return self.aem.score(windows)


def load_aem_version(root: DataRoot, version: str) -> AEMVersion:
    from evoeye.evaluation.monitors import AEM_DIR, load_aem
    from evoeye.monitor.card import thresholds_from_json

    meta = json.loads((root.path / AEM_DIR / version / "meta.json").read_text())
    if "thresholds" not in meta:
        raise KeyError(f"AEM {version} has no calibrated thresholds: it was not trained by a "
                       "campaign (train_aem_version)")
    return AEMVersion(load_aem(root, version), thresholds_from_json(meta["thresholds"]), meta)


def train_aem_version(root: DataRoot, scenario: str, *, train_runs: Runs, val_runs: Runs,
                      seed: int = 0, init_from: str | None = None, context_len: int | None = None,
                      horizon_s: float = DEFAULT_HORIZON_S, epochs: int | None = None,
                      splits: SplitSpec | None = None, **_ignored: Any) -> str:
    """Train (or fine-tune, `init_from`) an AEM on the collision-free windows of `train_runs`,
    calibrate its thresholds on `val_runs` (`calibrate_on_validation`), save it; its version. A
    version with the same training key (selection, seed, recipe, parent) is reused.
    `splits` and other FusionMonitor options (patience, …) do not apply and are ignored."""
    from evoeye.baselines.aem import AEMConfig, train_aem
    from evoeye.evaluation.calibration import calibrate_on_validation
    from evoeye.evaluation.dataset import load_runs
    from evoeye.evaluation.monitors import AEM_DIR, find_aem, training_key
    from evoeye.monitor.card import describe_selection, thresholds_to_json

    parent = load_aem_version(root, init_from) if init_from else None
    config = parent.aem.config if parent else AEMConfig(
        context_len=context_len or DEFAULT_CONTEXT_LEN)
    config = replace(config, seed=seed, **({"epochs": epochs} if epochs else {}))
    selection = {"train": describe_selection(train_runs), "val": describe_selection(val_runs)}
    key = training_key(scenario, selection, asdict(config), init_from, horizon_s)
    if (version := find_aem(root, key)) is not None:
        return version
    train = load_runs(root, scenario, train_runs, "train", context_len=config.context_len,
                      horizon_s=horizon_s)
    val = load_runs(root, scenario, val_runs, "val", context_len=config.context_len,
                    horizon_s=horizon_s)
    normal = train.windows.label == 0
    aem = train_aem(train.windows, normal, config, init=parent.aem if parent else None)
    thresholds = calibrate_on_validation(aem.score(val.windows), val.windows)
    aem.save(root.path / AEM_DIR, {
        "training_key": key, "logical_scenario": scenario, "parent": init_from,
        "horizon_s": horizon_s, "selection": selection,
        "train_windows": int(normal.sum()),
        "thresholds": thresholds_to_json(thresholds),
    })
    return aem.version


def initial_monitor(root: DataRoot, scenario: str) -> str:
    """The newest full FusionMonitor (all modules, L = 5) trained from scratch on `scenario`'s
    train split by filter — not on a hand-picked run list (e.g. the experiment's controls)."""
    from evoeye.monitor import list_versions, read_card
    from evoeye.monitor.model import MODULES

    cards = [(read_card(root, v), v) for v in list_versions(root)]
    mine = [(c.get("created_at", ""), v) for c, v in cards  # the full model, not an ablation
            if c.get("logical_scenario") == scenario and not c.get("parent")
            and tuple(c.get("modules", ())) == tuple(MODULES)
            and c.get("context_len") == DEFAULT_CONTEXT_LEN
            and c.get("selection", {}).get("train", {}).get("kind") == "filter"]
    if not mine:
        raise NoMonitorError(f"no monitor trained on {scenario!r} under {root}: train one "
                             f"first (`evoeye train --scenario {scenario}`) or name it")
    return max(mine)[1]


def initial_aem(root: DataRoot, scenario: str, train_ids: list[str], val_runs: Runs,
                horizon_s: float = DEFAULT_HORIZON_S) -> str:
    """AEM-Evo's G_0: the AEM trained from scratch on D_init (seed 0), trained once."""
    return train_aem_version(root, scenario, train_runs=train_ids, val_runs=val_runs, seed=0,
                             horizon_s=horizon_s)


def trainer_of(family: str):
    """The family's trainer (train_monitor's signature)."""
    if family == "aem":
        return train_aem_version

    def fusion(root, scenario, **kwargs) -> str:
        from evoeye.monitor import train_monitor

        return train_monitor(root, scenario, **kwargs)

    return fusion
