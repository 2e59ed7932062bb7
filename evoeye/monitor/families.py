"""The monitor families: one registry of what evoeye knows about each kind of trained monitor.

A family is everything the evaluation and the evolution need to handle its versions without
naming it: the prefix of its version ids, the folder its versions live in under the data root,
the files of a version (the weights, and the metadata recording their sha256), how to decode
checked weights into a monitor, how to train a version on a selection of runs, and how a
campaign finds its initial version G_0. `family_of(version)` finds a version's family by its
prefix; `load_version` loads any version, after the integrity check every family shares
(`read_model`: the weights must hash to the sha256 the metadata recorded).

The FusionMonitor ("fusion") is registered here; the baselines register theirs in
`evoeye.baselines.families` (AEM, context-only), imported by `evoeye.baselines`. Heavy modules
(torch, scikit-learn) are imported only when a version is loaded or trained.

Adding a family: a module with its monitor class, a decoder and (to be evolvable) a trainer and
an initial version, registered with `register_family` from a module its package imports.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from evoeye.monitor.inputs import MODULES
from evoeye.paths import DataRoot
from evoeye.store.windows import DEFAULT_CONTEXT_LEN

if TYPE_CHECKING:
    from evoeye.monitor.protocol import Thresholds
    from evoeye.store.windows import Windows

DEFAULT_FAMILY = "fusion"  # the monitor evoeye evolves, and whose G_0 defines the Hard Set


class MonitorLoadError(Exception):
    """A monitor version that cannot be loaded: missing, corrupt, or not matching its metadata."""


class NoMonitorError(LookupError):
    """A campaign needs a G_0 and none was named or trained for its scenario."""


class SavedMonitor(Protocol):
    """A loaded version: a Monitor that also knows its thresholds (None: never calibrated) and
    its metadata (card)."""

    name: str
    version: str
    thresholds: Thresholds | None
    card: dict[str, Any]

    @property
    def context_len(self) -> int: ...

    def score(self, windows: Windows) -> Any: ...


Decoder = Callable[[bytes, dict[str, Any], str], SavedMonitor]  # (checked weights, meta, version)
Trainer = Callable[..., str]  # (root, scenario, *, train_runs, val_runs, seed, init_from, …) → id
Initial = Callable[..., str]  # (root, scenario, *, train_runs, val_runs, horizon_s[, recipe])
# → G_0's id (`recipe`, for a family with `recipes`: the training recipe a G_0 it trains uses)
Fitter = Callable[..., SavedMonitor]  # (root, scenario, splits, *, seed, runs) → trained on the
# train split (or the RunFilter `runs`), with a training seed (None: the family's default)
SeedsTrainer = Callable[..., list[str]]  # Trainer's arguments, `seeds` for `seed` → ids


@dataclass(frozen=True)
class MonitorFamily:
    """One family of trained monitors and how to handle its versions (module doc)."""

    name: str  # e.g. "fusion", "aem"; a campaign's `family`
    label: str  # how reports name it, e.g. "FusionMonitor", "AEM"
    prefix: str  # every version id starts with it, e.g. "fusion-"
    folder: str  # its versions' folder under the data root, e.g. "monitors", "baselines/aem"
    model_file: str  # the weights in a version's folder
    meta_file: str  # the metadata (JSON, with "model_sha256") beside them
    decode: Decoder
    train: Trainer | None = None  # None: not evolvable
    initial: Initial | None = None  # None: a campaign must name its G_0
    fit: Fitter | None = None  # an RQ1 baseline trained on a scenario's train split
    recipes: bool = False  # its train and fit take a training recipe by name (`recipe=`)
    train_seeds: SeedsTrainer | None = None  # several seeds at once: the ids `train` gives
    # the `train` options that rebuild a version's network from scratch (None: its context)
    network: Callable[[SavedMonitor], dict[str, Any]] | None = None

    def network_of(self, monitor: SavedMonitor) -> dict[str, Any]:
        """What `train` needs to train `monitor`'s network again from scratch (a campaign's
        retraining keeps G_0's)."""
        return (self.network(monitor) if self.network is not None
                else {"context_len": monitor.context_len})

    @property
    def evolvable(self) -> bool:
        """A campaign can evolve it: it trains versions and finds a G_0."""
        return self.train is not None and self.initial is not None

    def versions_dir(self, root: DataRoot) -> Path:
        return root.path / self.folder

    def version_dir(self, root: DataRoot, version: str) -> Path:
        if not version or "/" in version or version.startswith("."):
            raise MonitorLoadError(f"not a monitor version id: {version!r}")
        return self.versions_dir(root) / version

    def versions(self, root: DataRoot) -> list[str]:
        """Every complete version under the root, oldest metadata first."""
        folder = self.versions_dir(root)
        if not folder.is_dir():
            return []
        done = [p for p in folder.iterdir()
                if not p.name.startswith(".") and (p / self.meta_file).exists()]
        return [p.name for p in sorted(done, key=lambda p: (p / self.meta_file).stat().st_mtime)]

    def read_meta(self, root: DataRoot, version: str) -> dict[str, Any]:
        """A version's metadata (MonitorLoadError if it is missing or not JSON)."""
        path = self.version_dir(root, version) / self.meta_file
        if not path.is_file():
            known = ", ".join(self.versions(root)[-5:]) or "none"
            raise MonitorLoadError(f"no monitor version {version!r} under {path.parents[1]} "
                                   f"(latest: {known})")
        return read_json(path)

    def load(self, root: DataRoot, version: str) -> SavedMonitor:
        """A saved version, ready to score, its weights checked against its metadata."""
        meta = self.read_meta(root, version)
        folder = self.version_dir(root, version)
        return self.decode(read_model(folder / self.model_file, folder / self.meta_file, meta),
                           meta, version)

    def find(self, root: DataRoot, key: str) -> str | None:
        """The version saved with this training key (`training_key`), if any."""
        for meta in sorted(self.versions_dir(root).glob(f"*/{self.meta_file}")):
            if read_json(meta).get("training_key") == key:
                return meta.parent.name
        return None


def read_json(path: Path) -> dict[str, Any]:
    """A metadata file as a dict (MonitorLoadError naming it if it cannot be read)."""
    try:
        return json.loads(path.read_bytes())
    except (OSError, ValueError) as e:
        raise MonitorLoadError(f"{path}: unreadable {path.name} ({e})") from e


def read_model(path: Path, meta_path: Path, meta: dict[str, Any]) -> bytes:
    """The bytes of a version's weights, if they hash to the sha256 `meta` records (the
    integrity check of every family); MonitorLoadError naming what is wrong otherwise."""
    try:
        data = path.read_bytes()
    except OSError as e:
        raise MonitorLoadError(f"{path}: cannot read checkpoint ({e.strerror or e})") from e
    expected = meta.get("model_sha256")
    if not expected:
        raise MonitorLoadError(f"{meta_path}: no model_sha256, so {path} cannot be checked")
    if hashlib.sha256(data).hexdigest() != expected:
        raise MonitorLoadError(f"{path}: checkpoint is corrupt or was modified (its sha256 "
                               f"differs from the one in {meta_path.name})")
    return data


def read_version(folder: str | os.PathLike[str], model_file: str, meta_file: str
                 ) -> tuple[bytes, dict[str, Any]]:
    """(checked weights, metadata) of a version folder outside any data root."""
    folder = Path(folder)
    meta = read_json(folder / meta_file)
    return read_model(folder / model_file, folder / meta_file, meta), meta


def training_key(*inputs: Any) -> str:
    """The key a trained version is found again by (`MonitorFamily.find`): a hash of everything
    its training used."""
    return hashlib.sha256(json.dumps(list(inputs), sort_keys=True, default=str).encode()
                          ).hexdigest()


FAMILIES: dict[str, MonitorFamily] = {}


def register_family(family: MonitorFamily) -> MonitorFamily:
    """Add a family to the registry (ValueError if its name or prefix is taken); the family."""
    clash = [f.name for f in FAMILIES.values()
             if f.name != family.name and (family.prefix.startswith(f.prefix)
                                           or f.prefix.startswith(family.prefix))]
    if family.name in FAMILIES or clash:
        raise ValueError(f"monitor family {family.name!r} (prefix {family.prefix!r}) clashes "
                         f"with {clash or [family.name]}")
    FAMILIES[family.name] = family
    return family


def family_of(version: str) -> MonitorFamily:
    """The family whose prefix starts `version` (MonitorLoadError if none does)."""
    for family in FAMILIES.values():
        if version.startswith(family.prefix):
            return family
    prefixes = ", ".join(f"{f.prefix}… ({f.name})" for f in FAMILIES.values())
    raise MonitorLoadError(f"{version!r} is no monitor version id; known: {prefixes}")


def load_version(root: DataRoot, version: str) -> SavedMonitor:
    """Any saved version, by its id."""
    return family_of(version).load(root, version)


def load_calibrated(root: DataRoot, version: str) -> SavedMonitor:
    """A version with its thresholds: every G_r is judged at the thresholds it was calibrated at
    when trained (MonitorLoadError for one saved without, e.g. an RQ1 baseline)."""
    monitor = load_version(root, version)
    if monitor.thresholds is None:
        raise MonitorLoadError(f"{version} has no calibrated thresholds: it was not trained by a "
                               "campaign")
    return monitor


def evolvable_families() -> list[str]:
    return [name for name, f in FAMILIES.items() if f.evolvable]


# -- the FusionMonitor ---------------------------------------------------------------------------
def initial_monitor(root: DataRoot, scenario: str, **_campaign: Any) -> str:
    """The newest full FusionMonitor (all modules, L = 5) trained from scratch on `scenario`'s
    train split by filter — not on a hand-picked run list (e.g. the experiment's controls).
    The campaign's D_init and validation split (`_campaign`) play no part: it is trained before."""
    fusion = FAMILIES[DEFAULT_FAMILY]
    cards = [(fusion.read_meta(root, v), v) for v in fusion.versions(root)]
    mine = [(c.get("created_at", ""), v) for c, v in cards  # the full model, not an ablation
            if c.get("logical_scenario") == scenario and not c.get("parent")
            and tuple(c.get("modules", ())) == tuple(MODULES)
            and c.get("context_len") == DEFAULT_CONTEXT_LEN
            and c.get("selection", {}).get("train", {}).get("kind") == "filter"]
    if not mine:
        raise NoMonitorError(f"no monitor trained on {scenario!r} under {root.path}: train one "
                             f"first (`evoeye train --scenario {scenario}`) or name it")
    return max(mine)[1]


def _decode_fusion(data: bytes, card: dict[str, Any], version: str) -> SavedMonitor:
    from evoeye.monitor.registry import decode_monitor

    return decode_monitor(data, card, version)


def _train_fusion(root: DataRoot, scenario: str | None = None, **kwargs: Any) -> str:
    from evoeye.monitor.train import train_monitor

    return train_monitor(root, scenario, **kwargs)


def _fusion_network(monitor: SavedMonitor) -> dict[str, Any]:
    """A FusionMonitor's network options: context, module inputs, dropout, derived kinematics."""
    c = monitor.net.config  # type: ignore[attr-defined]
    return {"context_len": c.context_len, "modules": list(c.modules), "dropout": c.dropout,
            "kinematics": c.kinematics}


def _train_fusion_seeds(root: DataRoot, scenario: str | None = None, **kwargs: Any
                        ) -> list[str]:
    from evoeye.monitor.train import train_monitors

    return train_monitors(root, scenario, **kwargs)


register_family(MonitorFamily(
    DEFAULT_FAMILY, "FusionMonitor", "fusion-", "monitors", "model.pt", "card.json",
    decode=_decode_fusion, train=_train_fusion, initial=initial_monitor, recipes=True,
    train_seeds=_train_fusion_seeds, network=_fusion_network,
))

