"""The trained baselines as monitor families: the AEM (evolvable: AEM-Evo), the context-only
control and the where-when control (the same without the ego's speed), each kept under
`<root>/baselines/<name>/<version>/` with `meta.json`.

RQ1 (`fit`): trained on the train split of a logical scenario (or any RunFilter, e.g. its
round-0 runs only) with a seed, and found again by a training key (a hash of the scenario,
split, config with its seed, horizon and run ids), so a later evaluation loads the version
instead of training again. AEM-Evo (paper RQ3, `train`): Algorithm 1 runs unchanged with
the AEM as the monitor — fine-tuned (or retrained) on the collision-free windows of D_r every
round, its thresholds calibrated on the validation runs and kept in `meta.json`; its G_0
(`initial`) is the AEM trained on D_init by the same recipe, found again by its training key.
"""

from __future__ import annotations

import functools
from dataclasses import asdict, replace
from typing import TYPE_CHECKING, Any

from evoeye.monitor.families import FAMILIES, MonitorFamily, register_family, training_key
from evoeye.paths import DataRoot
from evoeye.store.selection import RunFilter, Runs, SplitSpec
from evoeye.store.windows import DEFAULT_CONTEXT_LEN, DEFAULT_HORIZON_S

if TYPE_CHECKING:  # torch / scikit-learn are imported when an AEM / the control is used
    from evoeye.baselines.aem import AEMConfig, AEMMonitor
    from evoeye.baselines.context import ContextConfig, ContextOnlyMonitor


def _decode_aem(data: bytes, meta: dict[str, Any], version: str) -> AEMMonitor:
    from evoeye.baselines.aem import AEMMonitor

    return AEMMonitor.decode(data, meta)


def _decode_context(data: bytes, meta: dict[str, Any], version: str) -> ContextOnlyMonitor:
    from evoeye.baselines.context import ContextOnlyMonitor

    return ContextOnlyMonitor.decode(data, meta)


def _train_runs(scenario: str, splits: SplitSpec, runs: RunFilter | None) -> RunFilter:
    """The runs an RQ1 baseline trains on: `runs`, by default the scenario's train split."""
    return runs or RunFilter(logical_scenario=scenario, split="train", splits=splits)


def _train_ids(root: DataRoot, runs: RunFilter) -> list[str]:
    from evoeye.store import Warehouse, select_runs

    con = Warehouse(root).connect()
    try:
        table = select_runs(con, runs)
    finally:
        con.close()
    return sorted(table.column("scenario_id").to_pylist())


def _train_windows(root: DataRoot, runs: Runs, context_len: int, horizon_s: float):
    from evoeye.store import load_windows

    return load_windows(root, runs, context_len=context_len, horizon_s=horizon_s)


def _seeded(config, seed: int | None):
    """The config with its `seed` replaced (None: as it is)."""
    return config if seed is None else replace(config, seed=seed)


def _training_meta(key: str, scenario: str, splits: SplitSpec, horizon_s: float,
                   ids: list[str], n_windows: int) -> dict:
    """What meta.json records of an RQ1 baseline's training (the key it is found again by)."""
    return {"training_key": key, "logical_scenario": scenario, "splits": asdict(splits),
            "horizon_s": horizon_s, "train_scenarios": len(ids), "train_windows": n_windows}


def fit_aem(root: DataRoot, scenario: str,
            splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
            config: AEMConfig | None = None, *,
            horizon_s: float = DEFAULT_HORIZON_S, seed: int | None = None,
            runs: RunFilter | None = None, recipe: str | None = None) -> AEMMonitor:
    """The AEM of this scenario's train split (or of `runs`): loaded if trained before, else
    trained and saved; `config` (default: the AEM part of the training `recipe`, see
    `aem_config`) with `seed` in place of its own.

    Trained on the collision-free windows of the split: label 0 (all windows are before their
    run's collision, see `load_windows`)."""
    from evoeye.baselines.aem import aem_config, train_aem

    config = _seeded(config or aem_config(recipe), seed)
    runs = _train_runs(scenario, splits, runs)
    ids = _train_ids(root, runs)
    key = training_key(scenario, asdict(splits), config.record(), horizon_s, ids)
    if (version := AEM.find(root, key)) is not None:
        return AEM.load(root, version)
    train = _train_windows(root, runs, config.context_len, horizon_s)
    normal = train.label == 0
    monitor = train_aem(train, normal, config)
    monitor.save(AEM.versions_dir(root), _training_meta(key, scenario, splits, horizon_s, ids,
                                                        int(normal.sum())))
    return monitor


def fit_context_only(root: DataRoot, scenario: str,
                     splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
                     config: ContextConfig | None = None, *,
                     horizon_s: float = DEFAULT_HORIZON_S, seed: int | None = None,
                     runs: RunFilter | None = None,
                     name: str = "context-only") -> ContextOnlyMonitor:
    """The control `name` (context-only, where-when) of this scenario's train split (or of
    `runs`): loaded if trained before, else trained on every (eligible) training window and
    saved; `seed` replaces the config's."""
    from evoeye.baselines.context import ContextConfig, train_context_only

    family = FAMILIES[name]
    config = _seeded(config or ContextConfig(), seed)
    runs = _train_runs(scenario, splits, runs)
    ids = _train_ids(root, runs)
    key = training_key(name, scenario, asdict(splits), asdict(config), horizon_s, ids)
    if (version := family.find(root, key)) is not None:
        return family.load(root, version)
    train = _train_windows(root, runs, 1, horizon_s)
    monitor = train_context_only(train, config, name)
    monitor.save(family.versions_dir(root),
                 _training_meta(key, scenario, splits, horizon_s, ids, len(train)))
    return monitor


def train_aem_version(root: DataRoot, scenario: str, *, train_runs: Runs, val_runs: Runs,
                      seed: int = 0, init_from: str | None = None, context_len: int | None = None,
                      horizon_s: float = DEFAULT_HORIZON_S, epochs: int | None = None,
                      recipe: str | None = None, **_fusion_only: Any) -> str:
    """Train (or fine-tune, `init_from`) an AEM on the collision-free windows of `train_runs`,
    calibrate its thresholds on `val_runs` (`calibrate_on_validation`), save it; its version. A
    version with the same training key (selection, seed, recipe, parent) is reused. From
    scratch it trains by the AEM part of the training `recipe` (`aem_config`), fine-tuned by
    its parent's. FusionMonitor options (splits, patience, …) do not apply and are ignored."""
    from evoeye.baselines.aem import aem_config, train_aem
    from evoeye.monitor.calibration import calibrate_on_validation
    from evoeye.monitor.card import describe_selection, thresholds_to_card

    parent = AEM.load(root, init_from) if init_from else None
    config = parent.config if parent else aem_config(
        recipe, context_len=context_len or DEFAULT_CONTEXT_LEN)
    config = replace(config, seed=seed, **({"epochs": epochs} if epochs else {}))
    selection = {"train": describe_selection(train_runs), "val": describe_selection(val_runs)}
    key = training_key(scenario, selection, config.record(), init_from, horizon_s)
    if (version := AEM.find(root, key)) is not None:
        return version
    train = _train_windows(root, train_runs, config.context_len, horizon_s)
    val = _train_windows(root, val_runs, config.context_len, horizon_s)
    normal = train.label == 0
    aem = train_aem(train, normal, config, init=parent)
    thresholds = calibrate_on_validation(aem.score(val), val)
    aem.save(AEM.versions_dir(root), {
        "training_key": key, "logical_scenario": scenario, "parent": init_from,
        "horizon_s": horizon_s, "selection": selection,
        "train_windows": int(normal.sum()),
        **thresholds_to_card(thresholds),
    })
    return aem.version


def initial_aem(root: DataRoot, scenario: str, *, train_runs: Runs, val_runs: Runs,
                horizon_s: float = DEFAULT_HORIZON_S, recipe: str | None = None) -> str:
    """AEM-Evo's G_0: the AEM trained from scratch on D_init (seed 0) by the campaign's
    training recipe, trained once."""
    return train_aem_version(root, scenario, train_runs=list(train_runs), val_runs=val_runs,
                             seed=0, horizon_s=horizon_s, recipe=recipe)


AEM = register_family(MonitorFamily(
    "aem", "AEM", "aem-", "baselines/aem", "model.pt", "meta.json", decode=_decode_aem,
    train=train_aem_version, initial=initial_aem, fit=fit_aem, recipes=True,
))
CONTEXT_ONLY = register_family(MonitorFamily(
    "context-only", "context-only control", "ctx-", "baselines/context-only", "model.pkl",
    "meta.json", decode=_decode_context, fit=fit_context_only,
))
WHERE_WHEN = register_family(MonitorFamily(
    "where-when", "where-when control (no ego speed)", "ww-", "baselines/where-when",
    "model.pkl", "meta.json", decode=_decode_context,
    fit=functools.partial(fit_context_only, name="where-when"),
))
