"""Fixtures: seeded synthetic episodes and their logs (no simulator needed)."""

from __future__ import annotations

from pathlib import Path

import pytest

from evoeye.log import RunLog, read_run, write_episode
from evoeye.log.synthetic import synthetic_episode
from evoeye.sim.episode import Episode


@pytest.fixture(scope="module")
def episode() -> Episode:
    return synthetic_episode(n_frames=40, seed=7)


@pytest.fixture(scope="module")
def log_path(episode: Episode, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_episode(episode, tmp_path_factory.mktemp("log") / "run.mcap")


@pytest.fixture(scope="module")
def run(log_path: Path) -> RunLog:
    return read_run(log_path)
