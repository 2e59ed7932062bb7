"""Windows loaded inside `cached_parts()`: the same windows, each part decoded once."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.paths import DataRoot
from evoeye.store import ingest, load_windows
from evoeye.store import windows as windows_mod
from evoeye.store.ingest import ingest_batch
from evoeye.store.log_windows import read_logged_run
from evoeye.store.windows import Windows, cached_parts, part_cache

HIGHWAY = "highway-cut-in"


def same(a: Windows, b: Windows) -> None:
    for name in ("context", "context_mask", "label", "scenario_id", "frame", "t_s", "ego_xy_m"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for name, arr in a.features.arrays().items():  # the same layout, not just the same windows
        np.testing.assert_array_equal(arr, b.features.arrays()[name], err_msg=name)


@pytest.fixture
def decodes(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The parts decoded from Parquet inside a cache, by file name."""
    seen: list[str] = []
    real = windows_mod._decode

    def counting(path):
        seen.append(path.name)
        return real(path)

    monkeypatch.setattr(windows_mod, "_decode", counting)
    return seen


def test_each_part_is_decoded_once_and_the_windows_are_the_same(root: DataRoot, add_run,
                                                                decodes) -> None:
    for i in range(4):
        add_run(f"r{i}", n_frames=30, collision_frame=25 if i % 2 else None, seed=i,
                batch=f"b{i % 2}")
    ingest(root)
    some, every = ["r0", "r3"], None
    plain = {k: load_windows(root, r, context_len=3, horizon_s=1.0)
             for k, r in (("some", some), ("every", every))}
    with cached_parts():
        for _ in range(2):
            for key, runs in (("some", some), ("every", every)):
                same(load_windows(root, runs, context_len=3, horizon_s=1.0), plain[key])
    assert sorted(decodes) == sorted(set(decodes)) and len(decodes) == 2  # one part per batch
    assert part_cache() is None  # the block's cache is gone with it


def test_a_part_ingested_from_its_conversion_is_never_decoded(root: DataRoot, add_run,
                                                               decodes) -> None:
    logs = [add_run(f"c{i}", n_frames=30, collision_frame=20, seed=i, batch="evo-a")
            for i in range(2)]
    runs = [read_logged_run(log, context_len=5, horizon_s=1.0) for log in logs]
    with cached_parts():
        ingest_batch(root, (HIGHWAY, "evo-a"), runs)
        cached = load_windows(root, ["c0", "c1"], context_len=5, horizon_s=1.0)
    assert decodes == []
    same(cached, load_windows(root, ["c0", "c1"], context_len=5, horizon_s=1.0))
