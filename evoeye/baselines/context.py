"""Context-only control: gradient boosting on the run's clock, the ego's speed and its position.

It sees no module output at all — only the time since the run started, the ego's speed and its
x, y on the map, all from the ADS's localization (runtime signals, no ground truth). Whatever it
predicts, it predicts from *when* and *where* in a scenario the ego is, i.e. from the scenario
script. A learned monitor that cannot clearly beat it has learned the script, not how the ADS
fails. The classifier is scikit-learn's `HistGradientBoostingClassifier`, without its internal
validation split (so the same data and config give the same model), run on one OpenMP thread:
with its default pool on 2 shared cores a 20 K-row fit measured 76 s, on one thread 0.5 s. Saved
as a pickle whose sha256 is checked against `meta.json` before it is loaded (`read_version`).
"""

from __future__ import annotations

import functools
import hashlib
import json
import pickle
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier
from threadpoolctl import ThreadpoolController

from evoeye.monitor.families import read_version
from evoeye.monitor.protocol import Thresholds
from evoeye.store.features import CONTROL_FEATURES
from evoeye.store.windows import Windows

CONTEXT_INPUTS = ("t_s", "ego_speed_mps", "ego_x_m", "ego_y_m")
WHERE_WHEN_INPUTS = ("t_s", "ego_x_m", "ego_y_m")  # the same without the ego's speed
# the controls by name: (version prefix, inputs). The where-when control sees only the script's
# part — when and where the ego is — not the ego's speed, which is the ADS's own doing: where the
# stack drives into a conflict instead of braking, its speed shows it
CONTROLS = {"context-only": ("ctx-", CONTEXT_INPUTS), "where-when": ("ww-", WHERE_WHEN_INPUTS)}
SPEED = CONTROL_FEATURES.index("ego_speed_mps")
MODEL_FILE, META_FILE = "model.pkl", "meta.json"
THREADS = 1  # OpenMP threads for fit and predict (module doc)


@functools.cache
def _threadpools() -> ThreadpoolController:
    """The process's thread pools, found once: `threadpool_limits` scans the loaded libraries
    (/proc/self/maps) on every call, ≈ 30 ms — ruinous for one window scored per frame."""
    return ThreadpoolController()


def context_inputs(windows: Windows, inputs: tuple[str, ...] = CONTEXT_INPUTS) -> np.ndarray:
    """(B, len(inputs)) float64: the named inputs (of CONTEXT_INPUTS) at the frame each window
    ends at."""
    if windows.ego_xy_m is None:
        raise ValueError("these windows carry no ego position (load them with load_windows)")
    speed = windows.features.control[windows.context[:, -1], SPEED]  # (B,)
    every = np.column_stack([windows.t_s, speed, windows.ego_xy_m]).astype(np.float64)
    return every[:, [CONTEXT_INPUTS.index(name) for name in inputs]]


@dataclass(frozen=True)
class ContextConfig:
    """The classifier's hyper-parameters (recorded in meta.json)."""

    max_iter: int = 200
    learning_rate: float = 0.1
    max_leaf_nodes: int = 31
    min_samples_leaf: int = 40
    l2_regularization: float = 1.0
    seed: int = 0


@dataclass
class ContextOnlyMonitor:
    """A fitted classifier over CONTEXT_INPUTS; risk = its probability of the unsafe class."""

    config: ContextConfig
    model: HistGradientBoostingClassifier
    data_sha256: str  # of the training inputs and labels: same data and config, same version
    name: str = "context-only"  # a key of CONTROLS
    context_len: int = 1  # reads only the newest frame of a window
    thresholds: Thresholds | None = None  # never calibrated when saved: evaluate calibrates
    card: dict[str, Any] = field(default_factory=dict)  # meta.json of a saved version

    @property
    def version(self) -> str:
        h = hashlib.sha256(json.dumps(asdict(self.config), sort_keys=True).encode())
        h.update(self.data_sha256.encode())
        return f"{CONTROLS[self.name][0]}{h.hexdigest()[:12]}"

    @property
    def inputs(self) -> tuple[str, ...]:
        return CONTROLS[self.name][1]

    def score(self, windows: Windows) -> np.ndarray:
        if len(windows) == 0:
            return np.zeros(0)
        with _threadpools().limit(limits=THREADS):
            return self.model.predict_proba(context_inputs(windows, self.inputs))[:, 1]

    def save(self, folder: Path, meta: dict | None = None) -> Path:
        """Write `<folder>/<version>/model.pkl` and `meta.json`; the version folder."""
        out = Path(folder) / self.version
        out.mkdir(parents=True, exist_ok=True)
        blob = pickle.dumps(self.model, protocol=pickle.HIGHEST_PROTOCOL)
        (out / MODEL_FILE).write_bytes(blob)
        info = {"version": self.version, "name": self.name, "inputs": list(self.inputs),
                "config": asdict(self.config), "data_sha256": self.data_sha256,
                "model_sha256": hashlib.sha256(blob).hexdigest()}
        (out / META_FILE).write_text(json.dumps({**info, **(meta or {})}, indent=2) + "\n")
        return out

    @classmethod
    def decode(cls, blob: bytes, meta: dict[str, Any]) -> ContextOnlyMonitor:
        """The monitor of a checked model.pkl and its meta.json."""
        model = pickle.loads(blob)  # noqa: S301 (our own file, checked against its sha256)
        return cls(ContextConfig(**meta["config"]), model, meta["data_sha256"],
                   name=meta.get("name", "context-only"), card=meta)

    @classmethod
    def load(cls, version_dir: Path) -> ContextOnlyMonitor:
        """The saved monitor; MonitorLoadError for a model file whose sha256 differs from
        meta.json's."""
        return cls.decode(*read_version(version_dir, MODEL_FILE, META_FILE))


def context_classifier(config: ContextConfig = ContextConfig()  # noqa: B008
                       ) -> HistGradientBoostingClassifier:
    """The control's classifier, unfitted (also `evoeye audit`'s out-of-fold context check)."""
    return HistGradientBoostingClassifier(
        max_iter=config.max_iter, learning_rate=config.learning_rate,
        max_leaf_nodes=config.max_leaf_nodes, min_samples_leaf=config.min_samples_leaf,
        l2_regularization=config.l2_regularization, early_stopping=False,
        random_state=config.seed,
    )


def train_context_only(train: Windows, config: ContextConfig = ContextConfig(),  # noqa: B008
                       name: str = "context-only") -> ContextOnlyMonitor:
    """Fit the control `name` (of CONTROLS) on every window of `train` (eligible frames, their
    labels)."""
    x, y = context_inputs(train, CONTROLS[name][1]), train.label.astype(np.int8)  # (B, F), (B,)
    if len(np.unique(y)) < 2:
        raise ValueError(f"the {name} control needs both classes; {int(y.sum())} of "
                         f"{len(y)} training windows are unsafe")
    model = context_classifier(config)
    with _threadpools().limit(limits=THREADS):
        model.fit(x, y)
    data = hashlib.sha256(np.ascontiguousarray(x).tobytes() + y.tobytes()).hexdigest()
    return ContextOnlyMonitor(config, model, data, name=name)
