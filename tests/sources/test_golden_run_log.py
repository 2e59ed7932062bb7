"""The stored run log the golden Autoware bag and Apollo record are exported from is still what
the simulator writes: the same metadata, topics, schemas and message times, every value equal
but for the last bits a CPU's floating point may change (tests/data/autoware/make_golden.py)."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

from evoeye.log.reader import read_run

MAKE = Path(__file__).resolve().parents[1] / "data" / "autoware" / "make_golden.py"


def _make():
    spec = importlib.util.spec_from_file_location("make_golden_log", MAKE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _close(a, b, path="") -> list[str]:
    """Where a and b (decoded JSON) differ beyond 1e-9 relative; [] where they agree."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return [f"{path}: keys {sorted(a)} != {sorted(b)}"]
        return [d for k in a for d in _close(a[k], b[k], f"{path}.{k}")]
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} != {len(b)} items"]
        return [d for i, (x, y) in enumerate(zip(a, b, strict=True))
                for d in _close(x, y, f"{path}[{i}]")]
    if isinstance(a, float) and isinstance(b, float):
        return [] if math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12) else [f"{path}: {a} != {b}"]
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


def test_the_stored_golden_log_is_what_the_simulator_writes(tmp_path: Path) -> None:
    make = _make()
    for folder in ("stored", "again"):
        (tmp_path / folder).mkdir()
    stored = read_run(make.golden_log(tmp_path / "stored"))
    again = read_run(make.simulated_log(tmp_path / "again"))
    assert stored.metadata == again.metadata
    assert stored.schema_ids == again.schema_ids and stored.topics == again.topics
    assert len(stored.raw) >= 8  # every module's channel, the ground truth and the rest
    for topic in stored.topics:
        assert stored.log_times_ns(topic) == again.log_times_ns(topic), topic
        mine, theirs = stored.messages(topic), again.messages(topic)
        assert _close([m for _, m in mine], [m for _, m in theirs], topic) == []
