"""Two short simulated highway-cut-in runs (one collides) and their Autoware bags.

The round trip needs real runs: the ground-truth label is recomputed from the true footprints,
which only a simulated run keeps consistent with its own collision flag. 8 s each (the
colliding one collides at ≈ 6.8 s), simulated once per session (in one xdist worker). A bag is
a list of (log ns, topic, type, message) until `write_bag` writes it, so a test can spoil one.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from evoeye.log import write_episode
from evoeye.paths import DataRoot
from evoeye.scenarios import get_scenario
from evoeye.sim.episode import Episode
from evoeye.sim.runner import SimConfig, run_episode, run_spec
from evoeye.sources.autoware.config import Mapping
from evoeye.sources.autoware.export import RATES, bag_messages, write_bag
from evoeye.store import ingest

SCENARIO = "highway-cut-in"
DURATION_S = 8.0
SOURCES_DIR = Path(__file__).resolve().parent


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """One xdist group (`-n 2 --dist loadgroup`): the runs are simulated in one worker only."""
    for item in items:
        if SOURCES_DIR in Path(str(item.fspath)).resolve().parents:
            item.add_marker(pytest.mark.xdist_group("autoware"))


@dataclass
class SimRuns:
    """The native data root (both runs ingested), their episodes and logs, by scenario id."""

    root: DataRoot
    episodes: dict[str, Episode]
    logs: dict[str, Path]

    def collided(self) -> str:
        return next(s for s, e in self.episodes.items() if e.outcome.collided)

    def safe(self) -> str:
        return next(s for s, e in self.episodes.items() if not e.outcome.collided)


@pytest.fixture(scope="session")
def sim_runs(tmp_path_factory: pytest.TempPathFactory) -> SimRuns:
    root = DataRoot.resolve(tmp_path_factory.mktemp("native") / "data")
    space = get_scenario(SCENARIO)
    rng = np.random.default_rng(0)  # its first vector collides with seed 0, the second not
    episodes, logs = {}, {}
    for seed in range(2):
        spec = run_spec(SCENARIO, space.sample(rng), seed, batch="native")
        ep = run_episode(spec, SimConfig(duration_s=DURATION_S))
        path = root.run_log(SCENARIO, "native", spec.scenario_id)
        path.parent.mkdir(parents=True, exist_ok=True)
        logs[spec.scenario_id] = write_episode(ep, path)
        episodes[spec.scenario_id] = ep
    assert sorted(e.outcome.collided for e in episodes.values()) == [False, True]
    ingest(root)
    return SimRuns(root, episodes, logs)


@pytest.fixture(scope="session")
def messages(sim_runs: SimRuns):
    """messages(scenario_id, rates) → (metadata, [(ns, topic, type, msg)]) of a run's bag."""
    cache: dict = {}

    def get(sid: str, rates: str = "lossless"):
        if (sid, rates) not in cache:
            cache[sid, rates] = bag_messages(sim_runs.logs[sid], Mapping(), RATES[rates])
        return cache[sid, rates]

    return get


@pytest.fixture(scope="session")
def bag_at():
    """bag_at(path, msgs, identity=None): write messages as a bag folder (module doc)."""
    return _bag_at


def _bag_at(path: Path, msgs, identity: dict | None = None) -> Path:
    """Write `msgs` as a bag folder at `path` (with the run identity, if given)."""
    import orjson

    from evoeye.sources.autoware.bag import IDENTITY, OPTIONAL_IDENTITY, RUN_KEY

    kept = [*IDENTITY, *(k for k in OPTIONAL_IDENTITY if identity and k in identity)]
    custom = {RUN_KEY: orjson.dumps({k: identity[k] for k in kept}).decode()} \
        if identity else None
    return write_bag(path, msgs, custom)


def assert_same_windows(native_root: DataRoot, imported_root: DataRoot, ids: list[str],
                        tolerance: float) -> None:
    """The runs' windows in both warehouses: the same frames and labels (some unsafe), every
    input within `tolerance` (a lossless round trip's check)."""
    from evoeye.store import load_windows

    native, back = load_windows(native_root, ids), load_windows(imported_root, ids)
    assert len(native) == len(back) > 0
    assert np.array_equal(native.scenario_id, back.scenario_id)
    assert np.array_equal(native.frame, back.frame)
    assert np.array_equal(native.label, back.label) and native.label.sum() > 0
    a, b = native.arrays(), back.arrays()
    for name in a:
        assert a[name].shape == b[name].shape, name
        assert np.abs(a[name].astype(np.float64) - b[name]).max() <= tolerance, name


@pytest.fixture(scope="session")
def same_windows():
    """same_windows(native_root, imported_root, ids, tolerance): `assert_same_windows`."""
    return assert_same_windows
