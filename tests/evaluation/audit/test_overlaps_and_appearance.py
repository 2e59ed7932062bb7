"""Pass-through and pop-in on hand-built scenes."""

from __future__ import annotations

import numpy as np
import pytest
from audit_scenes import RATE_HZ, ActorPath, build_tracks

from evoeye.evaluation.audit.appearance import check_pop_in, late_appearances
from evoeye.evaluation.audit.overlaps import check_overlaps, longest_true_run

N = 60


def _overlapping_pair(overlap_frames: int, crashed: bool) -> list[ActorPath]:
    """Actor 2 drives along x at 10 m/s; actor 3 sits on its path at 30 m, so their boxes
    overlap for `overlap_frames` frames (5 m long cars: 1 m travel apart, 0.1 m per frame)."""
    ego = ActorPath.parked(0, N, -100.0, 10.0)
    mover = ActorPath.from_velocity(2, 0.0, 0.0, np.full(N, 10.0), np.zeros(N))
    start = 20
    x_parked = mover.x_m[start] + 5.0 + (overlap_frames - 1) * 0.5  # corner contact at `start`
    parked = ActorPath.parked(3, N, x_parked, 0.0)
    if crashed:
        flag = np.zeros(N, bool)
        flag[start:] = True
        mover.crashed, parked.crashed = flag.copy(), flag.copy()
    return [ego, mover, parked]


def test_two_npcs_driving_through_each_other_are_caught() -> None:
    (found,) = check_overlaps(build_tracks(_overlapping_pair(20, crashed=False)), RATE_HZ)
    assert (found.actor_a, found.actor_b) == (2, 3)
    assert found.duration_s >= 0.2


def test_a_recorded_contact_is_not_pass_through() -> None:
    assert check_overlaps(build_tracks(_overlapping_pair(20, crashed=True)), RATE_HZ) == ()


def test_a_brief_overlap_is_below_the_duration_bound() -> None:
    tracks = build_tracks(_overlapping_pair(20, crashed=False))
    assert check_overlaps(tracks, RATE_HZ, min_duration_s=10.0) == ()


def test_overlap_with_the_ego_is_not_npc_pass_through() -> None:
    paths = _overlapping_pair(20, crashed=False)
    paths[0].actor_id, paths[2].actor_id = 3, 0  # the parked car is now the ego
    assert check_overlaps(build_tracks(paths), RATE_HZ) == ()


def test_longest_true_run_per_column() -> None:
    mask = np.array([[1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 1, 0], [1, 1, 0]], bool)
    length, start = longest_true_run(mask)
    assert length.tolist() == [2, 4, 0]
    assert start.tolist()[:2] == [0, 1]


@pytest.mark.parametrize(("dist_m", "pop_in"), [(50.0, True), (120.0, False)])
def test_an_actor_appearing_late_near_the_ego_pops_in(dist_m: float, pop_in: bool) -> None:
    late = np.arange(N) >= 20
    paths = [ActorPath.parked(0, N, 0.0, 0.0),
             ActorPath.parked(1, N, 10.0, 0.0),  # 10 m away, there from the start
             ActorPath.from_velocity(5, dist_m, 0.0, np.full(N, 1e-9), np.zeros(N), present=late)]
    tracks = build_tracks(paths)
    (appearance,) = late_appearances(tracks)
    assert appearance.actor_id == 5 and appearance.t_s == pytest.approx(1.0)
    assert appearance.dist_m == pytest.approx(dist_m)
    assert (check_pop_in(tracks) == (appearance,)) is pop_in
