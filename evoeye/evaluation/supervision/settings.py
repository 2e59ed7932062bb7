"""What a supervision is: the batch, the triggers and their thresholds, the fallback, and where
its results live.

A supervision's results go to `<root>/supervision/<logical scenario>/<batch>/<key>/`, the key a
hash of every setting that changes a result (all but which logs are kept, and where), so a
supervision run again with the same settings finds its finished runs and one with other
settings starts apart:

    settings.json                        these settings
    runs/<scenario_id>.json              one record per run (`sweep.supervise_run`)
    logs/<trigger>/<id>.<trigger>.tNN.mcap  supervised runs' logs (threshold NN leads)

Nothing under `supervision/` is ingested: supervised runs never enter training data unless
asked (`logs_into_runs`: their logs go to `runs/<scenario>/<batch>-supervised/` instead, under
ids of their own, and the next `evoeye ingest` takes them in).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

from evoeye import __version__
from evoeye.criticality import Criticality
from evoeye.evaluation.supervision.triggers import TriggerSpec
from evoeye.paths import DataRoot, check_batch_name
from evoeye.sim.supervisor import FALLBACKS, FallbackConfig
from evoeye.store import SplitSpec
from evoeye.store.windows import DEFAULT_HORIZON_S

LOG_POLICIES = ("none", "collided", "all")  # which supervised simulations are logged
SETTINGS_FILE = "settings.json"


class SettingsMismatchError(ValueError):
    """A supervision folder holds other settings than those it is opened with."""


@dataclass(frozen=True)
class Settings:
    """Everything a supervision's results depend on (module doc)."""

    scenario: str
    batch: str
    triggers: tuple[TriggerSpec, ...]
    fallback: FallbackConfig = field(default_factory=FallbackConfig)
    consecutive: int = 1  # K: frames above the threshold that raise the alarm
    horizon_s: float = DEFAULT_HORIZON_S  # H: an intervention is true if a collision follows
    splits: SplitSpec = field(default_factory=SplitSpec)  # where the baselines were trained
    logs: str = "collided"  # LOG_POLICIES
    software_version: str = __version__
    logs_into_runs: bool = False  # the logs go where `evoeye ingest` takes them in
    criticality: Criticality = field(default_factory=Criticality)  # what justifies a brake

    def __post_init__(self) -> None:
        check_batch_name(self.batch)
        if self.logs not in LOG_POLICIES:
            raise ValueError(f"unknown log policy {self.logs!r}; known: {list(LOG_POLICIES)}")
        if self.consecutive < 1:
            raise ValueError(f"consecutive frames K must be at least 1, got {self.consecutive}")
        if not self.triggers:
            raise ValueError("a supervision needs at least one trigger")

    def to_dict(self) -> dict:
        return {"scenario": self.scenario, "batch": self.batch,
                "triggers": [t.to_dict() for t in self.triggers],
                "fallback": self.fallback.to_dict(), "consecutive": self.consecutive,
                "horizon_s": self.horizon_s, "splits": asdict(self.splits), "logs": self.logs,
                "software_version": self.software_version,
                "logs_into_runs": self.logs_into_runs, "criticality": self.criticality.to_dict()}

    @classmethod
    def of(cls, d: dict) -> Settings:
        return cls(d["scenario"], d["batch"], tuple(TriggerSpec.of(t) for t in d["triggers"]),
                   recorded_fallback(d["fallback"]), d["consecutive"], d["horizon_s"],
                   SplitSpec(**d["splits"]), d["logs"], d["software_version"],
                   d.get("logs_into_runs", False), Criticality(**d.get("criticality", {})))

    @property
    def key(self) -> str:
        """10 hex of the settings that change a result (all but where logs go)."""
        data = {k: v for k, v in self.to_dict().items() if k not in ("logs", "logs_into_runs")}
        return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:10]

    def folder(self, root: DataRoot) -> Path:
        return root.supervision / self.scenario / self.batch / self.key

    def trigger(self, name: str) -> TriggerSpec:
        return next(t for t in self.triggers if t.name == name)


def recorded_fallback(d: dict) -> FallbackConfig:
    """A recorded fallback; a value it lacks is the `comfort` fallback's, which every
    supervision used before fallbacks had names and stages (its dict lacks the stage)."""
    return FallbackConfig(**{**FALLBACKS["comfort"].to_dict(), **d})


def open_folder(root: DataRoot, settings: Settings) -> Path:
    """The supervision's folder, made with its settings.json (the log policy updated)."""
    folder = settings.folder(root)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / SETTINGS_FILE
    if path.exists():
        kept = Settings.of(json.loads(path.read_text()))
        if kept.key != settings.key:  # a hash collision, or a hand-edited file
            raise SettingsMismatchError(f"{path} holds other settings (key {kept.key})")
    path.write_text(json.dumps(settings.to_dict(), indent=1) + "\n")
    return folder


def read_settings(folder: Path) -> Settings:
    return Settings.of(json.loads((Path(folder) / SETTINGS_FILE).read_text()))
