"""Every bad bag gets one line naming the bag, the topic and the problem; the rest goes in.

Each bag here is the first 1.5 s of the safe simulated run (lossless rates), spoiled one way. A
refused bag leaves nothing behind (no run log, no warehouse row), and importing the batch again
adds nothing.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from evoeye.paths import DataRoot
from evoeye.sources.autoware.bag import BagError, read_bag
from evoeye.sources.autoware.config import Topics
from evoeye.sources.autoware.importer import import_bags
from evoeye.sources.autoware.typestore import typestore
from evoeye.store import Warehouse

T = Topics()
SECONDS_NS = 1_500_000_000
Msgs = list[tuple[int, str, str, object]]


def _without(topic: str, lo_s: float = -1.0, hi_s: float = 1e9) -> Callable[[Msgs], Msgs]:
    def spoil(msgs: Msgs) -> Msgs:
        return [m for m in msgs if not (m[1] == topic and lo_s < m[0] / 1e9 < hi_s)]
    return spoil


def _retyped(msgs: Msgs) -> Msgs:
    text = typestore().types["std_msgs/msg/String"]
    return [(t, topic, "std_msgs/msg/String", text(data="?")) if topic == T.objects
            else (t, topic, kind, m) for t, topic, kind, m in msgs]


def _edit(topic: str, which: Callable[[int], bool], change: Callable[[object], None]
          ) -> Callable[[Msgs], Msgs]:
    def spoil(msgs: Msgs) -> Msgs:
        out, seen = [], 0
        for t, top, kind, m in msgs:
            if top == topic:
                if which(seen):
                    m = copy.deepcopy(m)
                    change(m)
                seen += 1
            out.append((t, top, kind, m))
        return out
    return spoil


def _stamp_back(m) -> None:
    m.header.stamp.sec, m.header.stamp.nanosec = 0, 0


def _swap_times(m) -> None:
    a, b = m.points[3].time_from_start, m.points[4].time_from_start
    m.points[3].time_from_start, m.points[4].time_from_start = b, a


def _zero_times(m) -> None:
    for p in m.points:
        p.time_from_start.sec, p.time_from_start.nanosec = 0, 0


def _stretch_quaternion(m) -> None:
    q = m.pose.pose.orientation
    q.x, q.y, q.z, q.w = 2 * q.x, 2 * q.y, 2 * q.z, 2 * q.w


def _empty(m) -> None:
    m.objects = []


REFUSED = {  # name: (spoiler, topic named, problem named)
    "unknown-type": (_retyped, T.objects, "unknown message type std_msgs/msg/String"),
    "missing-topic": (_without(T.control), T.control, "missing required topic"),
    "no-odometry": (_without(T.odometry), T.odometry, "no ego odometry"),
    "out-of-order": (_edit(T.trajectory, lambda i: i == 10, _stamp_back), T.trajectory,
                     "out-of-order stamps"),
    "gap": (_without(T.control, 0.5, 1.2), T.control,
            "gap of 0.55 s before the frame at 1.05 s"),
    "vanishing-objects": (_without(T.objects, 0.9), T.objects, "gap of 0.55"),
    "unsorted-times": (_edit(T.trajectory, lambda i: i == 5, _swap_times), T.trajectory,
                       "trajectory times are not increasing"),
    "unnormalised": (_edit(T.odometry, lambda i: i == 7, _stretch_quaternion), T.odometry,
                     "quaternion of norm 2 is not normalised"),
}


@pytest.fixture(scope="module")
def short(sim_runs, messages) -> tuple[dict, Msgs]:
    meta, msgs = messages(sim_runs.safe())
    return meta, [m for m in msgs if m[0] < SECONDS_NS]


@pytest.fixture(scope="module")
def bags(short, bag_at, tmp_path_factory) -> dict[str, Path]:
    meta, msgs = short
    base = tmp_path_factory.mktemp("bags")
    out = {"good": bag_at(base / "good", msgs)}
    for name, (spoil, _, _) in REFUSED.items():
        out[name] = bag_at(base / name, spoil(msgs))
    out["empty-objects"] = bag_at(base / "empty-objects",
                                  _edit(T.objects, lambda i: i < 10, _empty)(msgs))
    out["zero-times"] = bag_at(base / "zero-times",
                               _edit(T.trajectory, lambda i: True, _zero_times)(msgs))
    truncated = bag_at(base / "truncated", msgs)
    mcap = next(truncated.glob("*.mcap"))
    mcap.write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    out["truncated"] = truncated
    return out


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_a_bad_bag_is_refused_with_one_line_naming_bag_topic_and_problem(bags, name) -> None:
    _, topic, problem = REFUSED[name]
    with pytest.raises(BagError) as refused:
        read_bag(bags[name])
    line = str(refused.value)
    assert "\n" not in line
    assert line.startswith(f"{bags[name]}: {topic}: "), line
    assert problem in line, line


def test_a_truncated_bag_is_refused_naming_it(bags) -> None:
    with pytest.raises(BagError, match=r"truncated: \(bag\): (unreadable|bad) bag"):
        read_bag(bags["truncated"])


def test_empty_object_lists_go_in_with_a_note_and_no_obstacle(bags) -> None:
    run = read_bag(bags["empty-objects"])
    assert len(run.frames) == 30
    counts = [len(f.messages["/ads/perception/obstacles"]["track_id"]) for f in run.frames]
    assert counts[:10] == [0] * 10 and min(counts[10:]) > 0
    assert run.notes == [f"{bags['empty-objects']}: {T.objects}: empty object list in 10 of "
                         "30 frames"]


def test_all_zero_trajectory_times_are_rebuilt_from_arc_length_with_a_note(bags) -> None:
    good, rebuilt = read_bag(bags["good"]), read_bag(bags["zero-times"])
    assert any("all-zero time_from_start in 30 trajectories" in n for n in rebuilt.notes)
    for a, b in zip(good.frames, rebuilt.frames, strict=True):
        pa, pb = a.messages["/ads/planning/trajectory"], b.messages["/ads/planning/trajectory"]
        n = min(len(pa["x_m"]), len(pb["x_m"]))
        # times from speed and distance put the points where the planner's times did, to
        # within the speed's change over a step
        assert np.abs(np.subtract(pa["x_m"][:n], pb["x_m"][:n])).max() < 1.0


def test_a_batch_takes_the_good_bags_refuses_the_bad_and_reruns_without_duplicates(
        bags, tmp_path: Path) -> None:
    root = DataRoot.resolve(tmp_path / "data")
    batch = [bags[n] for n in ("good", "unknown-type", "gap", "truncated", "zero-times")]
    report = import_bags(root, batch)
    assert [line.split(": ")[0] for line in report.failed] == [str(b) for b in batch[1:4]]
    accepted = sorted(report.labels)
    assert len(accepted) == 2 and sorted(report.ingest[0].ingested) == accepted
    logs = sorted(p.name for p in root.runs.rglob("*.mcap"))
    assert logs == [f"{sid}.mcap" for sid in accepted]  # nothing of the refused bags
    again = import_bags(root, batch)
    assert again.failed == report.failed and again.ingest[0].ingested == []
    assert again.ingest[0].skipped == 2 and again.labels == {}  # not even converted again
    count = Warehouse(root).sql("SELECT count(*) AS n FROM scenarios").column("n").to_pylist()
    assert count == [2]
