"""`make test` runs the suite with `--dist loadgroup`: a test module or folder marked with an
xdist_group (the flows' Prefect server, the module fixtures built once) runs on one worker. A
pytest that silently drops the groups (9.2, pytest-xdist#1386) fails here, not in the timings."""

import pytest

pytestmark = pytest.mark.xdist_group("grouping-check")


def test_a_marked_test_runs_in_its_group_under_loadgroup(request: pytest.FixtureRequest) -> None:
    grouped = bool(getattr(request.config.option, "loadgroup", False))  # set on xdist workers
    # xdist carries the group in the node id it schedules by
    assert request.node.nodeid.endswith("@grouping-check") == grouped
    assert request.node.get_closest_marker("xdist_group").args == ("grouping-check",)
