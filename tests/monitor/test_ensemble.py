"""Ensembles of from-scratch members: their seeds, their mean risk, their calibration."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.monitor.ensemble import MAX_MEMBERS, mean_risk, member_seeds


def test_member_0_keeps_the_seed_and_the_others_are_distinct_and_stable() -> None:
    seeds = member_seeds(4_000_123, 5)
    assert seeds[0] == 4_000_123 and len(set(seeds)) == 5
    assert member_seeds(4_000_123, 3) == seeds[:3]  # k members are the first k of more
    assert member_seeds(4_000_123, 1) == [4_000_123]
    assert member_seeds(4_000_124, 3)[1:] != seeds[1:3]  # another checkpoint, other members
    assert all(0 <= s < 2**32 for s in seeds)  # numpy and torch both take them


@pytest.mark.parametrize("k", [0, -1, MAX_MEMBERS + 1])
def test_a_bad_member_count_is_refused_in_one_line(k) -> None:
    with pytest.raises(ValueError, match=f"an ensemble has 1 to {MAX_MEMBERS} members, got {k}"):
        member_seeds(0, k)


def test_the_mean_risk_is_the_mean_of_the_members() -> None:
    scores = [np.array([0.1, 0.9, 0.5], np.float32), np.array([0.3, 0.7, 0.5], np.float32)]
    assert mean_risk(scores) == pytest.approx([0.2, 0.8, 0.5])
    assert mean_risk(scores[:1]).tolist() == scores[0].astype(np.float64).tolist()
