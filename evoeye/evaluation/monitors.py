"""Which monitors to evaluate: the baselines by name, FusionMonitors by version (a registry).

TTC and RSS are rules and need no data. AEM and the context-only control are trained on the
train split of the logical scenario and kept under `<root>/baselines/<aem|context-only>/<version>/`;
a later call with the same training set, split and config loads one instead of training again.
FusionMonitors come from `evoeye.monitor` (`load_monitor`, `train_monitor`), imported only when
asked for.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Iterable
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from evoeye.baselines.rss import RSSMonitor
from evoeye.baselines.ttc import TTCMonitor
from evoeye.evaluation.dataset import load_split
from evoeye.monitor.protocol import Monitor
from evoeye.paths import DataRoot
from evoeye.store import RunFilter, SplitSpec, Warehouse, select_runs
from evoeye.store.windows import DEFAULT_HORIZON_S

if TYPE_CHECKING:  # torch / scikit-learn are imported when an AEM / the control is asked for
    from evoeye.baselines.aem import AEMConfig, AEMMonitor
    from evoeye.baselines.context import ContextConfig, ContextOnlyMonitor

AEM_DIR = Path("baselines") / "aem"
CONTEXT_DIR = Path("baselines") / "context-only"



def _train_ids(root: DataRoot, scenario: str, splits: SplitSpec) -> list[str]:
    con = Warehouse(root).connect()
    try:
        runs = select_runs(con, RunFilter(logical_scenario=scenario, split="train", splits=splits))
    finally:
        con.close()
    return sorted(runs.column("scenario_id").to_pylist())


def training_key(*inputs) -> str:
    """The key a trained baseline (AEM, context-only) is found again by: a hash of everything
    its training used."""
    return hashlib.sha256(json.dumps(list(inputs), sort_keys=True, default=str).encode()
                          ).hexdigest()


def find_saved(root: DataRoot, folder: Path, key: str) -> str | None:
    """The version saved under `<root>/<folder>/` with this training key, if any."""
    for meta in sorted((root.path / folder).glob("*/meta.json")):
        if json.loads(meta.read_text()).get("training_key") == key:
            return meta.parent.name
    return None


def find_aem(root: DataRoot, key: str) -> str | None:
    """The version of the AEM saved with this training key, if any."""
    return find_saved(root, AEM_DIR, key)


def fit_aem(root: DataRoot, scenario: str,
            splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
            config: AEMConfig | None = None, *,
            horizon_s: float = DEFAULT_HORIZON_S) -> AEMMonitor:
    """The AEM of this scenario's train split: loaded if trained before, else trained and saved.

    Trained on the collision-free windows of the split: label 0 (all windows are before their
    run's collision, see `load_windows`)."""
    from evoeye.baselines.aem import AEMConfig, train_aem

    config = config or AEMConfig()
    ids = _train_ids(root, scenario, splits)
    key = training_key(scenario, asdict(splits), asdict(config), horizon_s, ids)
    if (version := find_aem(root, key)) is not None:
        return load_aem(root, version)
    train = load_split(root, scenario, "train", splits, context_len=config.context_len,
                       horizon_s=horizon_s)
    normal = train.windows.label == 0
    monitor = train_aem(train.windows, normal, config)
    monitor.save(root.path / AEM_DIR, _training_meta(key, scenario, splits, horizon_s, ids,
                                                     int(normal.sum())))
    return monitor


def _training_meta(key: str, scenario: str, splits: SplitSpec, horizon_s: float,
                   ids: list[str], n_windows: int) -> dict:
    """What meta.json records of an RQ1 baseline's training (the key it is found again by)."""
    return {"training_key": key, "logical_scenario": scenario, "splits": asdict(splits),
            "horizon_s": horizon_s, "train_scenarios": len(ids), "train_windows": n_windows}


def _version_dir(root: DataRoot, folder: Path, version: str) -> Path:
    """`<root>/<folder>/<version>/`, or a KeyError if no version is saved there."""
    path = root.path / folder / version
    if not (path / "meta.json").is_file():
        raise KeyError(f"no version {version!r} under {path.parent}")
    return path


def load_aem(root: DataRoot, version: str) -> AEMMonitor:
    """A saved AEM by version."""
    from evoeye.baselines.aem import AEMMonitor

    return AEMMonitor.load(_version_dir(root, AEM_DIR, version))


def fit_context_only(root: DataRoot, scenario: str,
                     splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
                     config: ContextConfig | None = None, *,
                     horizon_s: float = DEFAULT_HORIZON_S) -> ContextOnlyMonitor:
    """The context-only control of this scenario's train split: loaded if trained before, else
    trained on every (eligible) training window and saved."""
    from evoeye.baselines.context import ContextConfig, train_context_only

    config = config or ContextConfig()
    ids = _train_ids(root, scenario, splits)
    key = training_key("context-only", scenario, asdict(splits), asdict(config), horizon_s, ids)
    if (version := find_saved(root, CONTEXT_DIR, key)) is not None:
        return load_context_only(root, version)
    train = load_split(root, scenario, "train", splits, context_len=1, horizon_s=horizon_s)
    monitor = train_context_only(train.windows, config)
    monitor.save(root.path / CONTEXT_DIR, _training_meta(key, scenario, splits, horizon_s, ids,
                                                         len(train)))
    return monitor


def load_context_only(root: DataRoot, version: str) -> ContextOnlyMonitor:
    """A saved context-only control by version."""
    from evoeye.baselines.context import ContextOnlyMonitor

    return ContextOnlyMonitor.load(_version_dir(root, CONTEXT_DIR, version))


BaselineBuilder = Callable[[DataRoot, str, SplitSpec], Monitor]
BASELINES: dict[str, BaselineBuilder] = {
    "ttc": lambda root, scenario, splits: TTCMonitor(),
    "rss": lambda root, scenario, splits: RSSMonitor(),
    "aem": lambda root, scenario, splits: fit_aem(root, scenario, splits),
    "context-only": lambda root, scenario, splits: fit_context_only(root, scenario, splits),
}
SAVED_BASELINES: dict[str, Callable[[DataRoot, str], Monitor]] = {  # version prefix → loader
    "aem-": load_aem,
    "ctx-": load_context_only,
}


def baseline_monitors(root: DataRoot, scenario: str,
                      splits: SplitSpec = SplitSpec(),  # noqa: B008 (frozen dataclass)
                      names: Iterable[str] = tuple(BASELINES)) -> list[Monitor]:
    """The named baselines, ready to score windows of `scenario`."""
    names = list(names)
    unknown = [n for n in names if n not in BASELINES]
    if unknown:
        raise KeyError(f"unknown baseline(s) {unknown}; known: {sorted(BASELINES)}")
    return [BASELINES[n](root, scenario, splits) for n in names]


def fusion_api() -> tuple[Callable, Callable] | None:
    """(train_monitor, load_monitor) from evoeye.monitor (or its train / registry modules), or
    None before they exist."""
    try:
        from evoeye.monitor import load_monitor, train_monitor
    except ImportError:
        try:
            from evoeye.monitor.registry import load_monitor
            from evoeye.monitor.train import train_monitor
        except ImportError:
            return None
    return train_monitor, load_monitor


def load_monitors(root: DataRoot, versions: Iterable[str]) -> list[Monitor]:
    """Trained monitors by version: saved baselines (AEM, context-only) from here, every other
    from evoeye.monitor."""
    out: list[Monitor] = []
    for v in versions:
        loader = next((f for p, f in SAVED_BASELINES.items() if v.startswith(p)), None)
        if loader is not None:
            out.append(loader(root, v))
            continue
        api = fusion_api()
        if api is None:
            raise RuntimeError(f"cannot load monitor {v!r}: evoeye.monitor has no load_monitor")
        out.append(api[1](root, v))
    return out


def train_fusion(root: DataRoot, scenario: str, *, context_len: int = 5,
                 modules: tuple[str, ...] | None = None, seed: int = 0,
                 splits: SplitSpec | None = None, **overrides) -> Monitor:
    """Train (or let the registry reuse) a FusionMonitor for `scenario` and load it;
    `overrides` go to train_monitor (epochs=…, lr=…)."""
    api = fusion_api()
    if api is None:
        raise RuntimeError("evoeye.monitor has no train_monitor yet: FusionMonitor unavailable")
    train_monitor, load_monitor = api
    kwargs: dict = {"scenario": scenario, "context_len": context_len, "seed": seed,
                    **overrides}
    if modules is not None:
        kwargs["modules"] = modules
    if splits is not None:
        kwargs["splits"] = splits
    version = train_monitor(root, **kwargs)
    return load_monitor(root, version)


def monitor_context_len(monitor: Monitor, default: int = 5) -> int:
    """The context length L a monitor reads (its `context_len`, else `default`)."""
    return int(getattr(monitor, "context_len", default) or default)


def check_scores(monitor: Monitor, scores: np.ndarray, n: int) -> np.ndarray:
    """The monitor's scores as (n,) float64 in [0, 1], or a clear error."""
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    if s.shape != (n,):
        raise ValueError(f"{monitor.name} returned {s.shape} scores for {n} windows")
    if not np.isfinite(s).all() or s.min(initial=0.0) < 0.0 or s.max(initial=0.0) > 1.0:
        raise ValueError(f"{monitor.name} returned scores outside [0, 1]")
    return s
