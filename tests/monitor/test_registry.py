"""Versions on disk: round trip, safe loading, clear errors, the Monitor protocol."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
import torch

from evoeye.monitor import Monitor
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.model import FusionConfig, FusionNet
from evoeye.monitor.registry import (
    CARD_FILE,
    MODEL_FILE,
    MonitorLoadError,
    list_versions,
    load_monitor,
    load_net,
    save_version,
    version_dir,
)
from evoeye.paths import DataRoot
from evoeye.store import load_windows


@pytest.fixture
def copy_of(tiny, trained, tmp_path):
    """A private copy of the trained version, safe to damage."""
    root = DataRoot.resolve(tmp_path / "root")
    shutil.copytree(version_dir(tiny.root, trained), root.monitors / trained)
    return root


def test_save_load_round_trip_gives_identical_scores(tiny, trained: str) -> None:
    monitor = load_monitor(tiny.root, trained)
    windows = load_windows(tiny.root, context_len=5, horizon_s=tiny.horizon_s)
    scores = monitor.score(windows)
    again = load_monitor(tiny.root, trained).score(windows)
    assert np.array_equal(scores, again) and scores.shape == (len(windows),)
    assert scores.dtype == np.float32 and ((scores >= 0) & (scores <= 1)).all()
    # saving the loaded net again lands on the same version (content-addressed)
    assert save_version(tiny.root, monitor.net, monitor.card) == trained


def test_loaded_monitor_implements_the_monitor_protocol(tiny, trained: str) -> None:
    monitor = load_monitor(tiny.root, trained)
    assert isinstance(monitor, Monitor)
    assert monitor.name == "fusion" and monitor.version == trained
    assert monitor.context_len == 5 and monitor.horizon_s == tiny.horizon_s
    assert monitor.thresholds.at(0.01) >= monitor.thresholds.at(0.05)
    assert not monitor.net.training
    assert trained in list_versions(tiny.root)


def test_scoring_windows_of_another_length_is_refused(tiny, trained: str) -> None:
    monitor = load_monitor(tiny.root, trained)
    with pytest.raises(ValueError, match="L = 5"):
        monitor.score(load_windows(tiny.root, tiny.ids["val"], context_len=3))


def test_a_modified_checkpoint_is_refused(copy_of, trained: str) -> None:
    path = copy_of.monitors / trained / MODEL_FILE
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(MonitorLoadError, match="corrupt or was modified"):
        load_monitor(copy_of, trained)


def test_a_truncated_or_foreign_checkpoint_is_refused(tmp_path) -> None:
    path = tmp_path / MODEL_FILE
    path.write_bytes(b"definitely not a torch checkpoint")
    with pytest.raises(MonitorLoadError, match="not a valid FusionMonitor checkpoint"):
        load_net(path)
    # a checkpoint whose weights do not fit its config
    net = FusionNet(FusionConfig(context_len=3))
    config = FusionConfig(context_len=5).to_dict()
    torch.save({"config": config, "state_dict": net.state_dict()}, path)
    with pytest.raises(MonitorLoadError, match="size mismatch"):
        load_net(path)
    # pickled code is never run: weights_only refuses arbitrary objects
    torch.save({"config": config, "state_dict": {}, "payload": FusionMonitor}, path)
    with pytest.raises(MonitorLoadError, match="not a valid"):
        load_net(path)


def test_missing_version_and_missing_checkpoint_are_named(copy_of, trained: str) -> None:
    with pytest.raises(MonitorLoadError, match="no monitor version 'fusion-nope'"):
        load_monitor(copy_of, "fusion-nope")
    (copy_of.monitors / trained / MODEL_FILE).unlink()
    with pytest.raises(MonitorLoadError, match="cannot read checkpoint"):
        load_monitor(copy_of, trained)
    (copy_of.monitors / trained / CARD_FILE).write_text("{not json")
    with pytest.raises(MonitorLoadError, match="unreadable card"):
        load_monitor(copy_of, trained)
    with pytest.raises(MonitorLoadError, match="not a monitor version"):
        load_monitor(copy_of, "../etc")


def test_save_is_atomic_and_leaves_no_temporary_folders(tiny, trained: str) -> None:
    folder = version_dir(tiny.root, trained).parent
    assert not [p for p in folder.iterdir() if p.name.startswith(".")]
    assert sorted(p.name for p in version_dir(tiny.root, trained).iterdir()) == [
        CARD_FILE, MODEL_FILE]
