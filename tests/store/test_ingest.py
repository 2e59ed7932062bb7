"""Ingest: round trip, idempotence, quarantine, crash safety, the single-writer lock."""

from __future__ import annotations

import numpy as np
import pytest

from evoeye.log import read_run
from evoeye.paths import DataRoot
from evoeye.store import Warehouse, WarehouseLockedError, WriterLock, ingest
from evoeye.store.ingest import REASON_SUFFIX
from evoeye.store.parts import PartStore


def _counts(root: DataRoot) -> tuple[int, int, int]:
    t = Warehouse(root).sql(
        "SELECT (SELECT count(*) FROM scenarios), (SELECT count(*) FROM frames), "
        "(SELECT count(*) FROM frame_features)"
    )
    return tuple(int(t.column(i)[0].as_py()) for i in range(3))


def _parquet_files(root: DataRoot) -> list[str]:
    return sorted(str(p.relative_to(root.path)) for p in root.warehouse.rglob("*.parquet"))


def test_round_trip_keeps_every_signal(root: DataRoot, episode_factory, log_writer) -> None:
    episode = episode_factory("rt-1", n_frames=12, seed=3, collision_frame=9)
    log = log_writer(root, episode)
    report = ingest(root)
    assert report.ingested == ["rt-1"] and report.frames == 12 and not report.quarantined

    wh = Warehouse(root)
    row = wh.sql("SELECT * FROM scenarios").to_pylist()[0]
    assert row["scenario_id"] == "rt-1"
    assert row["logical_scenario"] == "highway-cut-in" and row["batch"] == "b000"
    assert row["params"] == pytest.approx(list(episode.spec.params))
    assert row["collided"] and row["collision_time_s"] == pytest.approx(9 / 20)
    assert row["n_frames"] == 12 and row["status"] == "ok"
    assert row["log_path"] == root.relative(log)

    frames = wh.sql("SELECT * FROM frames ORDER BY frame").to_pylist()
    assert [f["frame"] for f in frames] == list(range(12))
    for f, src in zip(frames, episode.frames, strict=True):
        m = src.messages
        assert f["t_s"] == pytest.approx(src.scene.t_s)
        assert f["loc_speed_mps"] == pytest.approx(m.localization.speed_mps)
        np.testing.assert_allclose(f["obs_x_m"], m.obstacles.x_m, rtol=1e-6)
        assert f["obs_class"] == list(m.obstacles.obj_class)
        np.testing.assert_allclose(np.array(f["pred_y_m"]), m.predictions.y_m, rtol=1e-6)
        np.testing.assert_allclose(f["plan_speed_mps"], m.plan.speed_mps, rtol=1e-6)
        assert f["plan_decision"] == m.plan.decision
        assert f["ctrl_throttle"] == pytest.approx(m.control.throttle)
        assert f["gt_x_m"] == pytest.approx(src.scene.x_m[0])  # the ego, actor 0
        assert f["gt_vy_mps"] == pytest.approx(src.scene.vy_mps[0])
        assert f["gt_ego_collision"] == (f["frame"] >= 9)


def test_reingest_adds_nothing(root: DataRoot, add_run) -> None:
    for i in range(3):
        add_run(f"re-{i}", seed=i)
    first = ingest(root)
    files, counts = _parquet_files(root), _counts(root)
    assert len(first.ingested) == 3 and counts == (3, 90, 90)

    again = ingest(root)
    assert again.ingested == [] and again.skipped == 3 and again.frames == 0
    assert _parquet_files(root) == files and _counts(root) == counts

    add_run("re-3", seed=3)  # a new log: only it is added
    third = ingest(root)
    assert third.ingested == ["re-3"] and third.skipped == 3 and _counts(root) == (4, 120, 120)


def test_duplicate_scenario_and_unfinished_logs_are_not_ingested(root: DataRoot, add_run) -> None:
    log = add_run("dup", seed=1)
    copy = root.runs / "highway-cut-in" / "other-batch" / "dup.mcap"
    copy.parent.mkdir(parents=True)
    copy.write_bytes(log.read_bytes())
    unfinished = log.with_name("half.mcap.123.tmp")
    unfinished.write_bytes(log.read_bytes()[:100])
    report = ingest(root)
    assert report.ingested == ["dup"] and len(report.duplicates) == 1
    assert not report.quarantined and unfinished.exists()  # left alone for its writer
    assert _counts(root)[0] == 1


def test_corrupt_and_truncated_logs_are_quarantined_by_name(root: DataRoot, add_run) -> None:
    good = [add_run(f"ok-{i}", seed=i) for i in range(2)]
    truncated = add_run("truncated", seed=5)
    truncated.write_bytes(truncated.read_bytes()[: truncated.stat().st_size // 2])
    corrupt = add_run("corrupt", seed=6)
    data = bytearray(corrupt.read_bytes())
    data[len(data) // 3 : len(data) // 3 + 64] = b"\x00" * 64  # inside a chunk: CRC fails
    corrupt.write_bytes(bytes(data))

    report = ingest(root)
    assert sorted(report.ingested) == ["ok-0", "ok-1"]
    bad = dict(report.quarantined)
    assert set(bad) == {root.relative(truncated), root.relative(corrupt)}
    assert "truncated" in bad[root.relative(truncated)]
    for log in (truncated, corrupt):
        assert not log.exists()  # moved out of runs/
        moved = root.quarantine / log.relative_to(root.runs)
        assert moved.exists()
        reason = moved.with_name(moved.name + REASON_SUFFIX).read_text()
        assert str(log.name) in reason  # the reader's error names the file
    assert all(g.exists() for g in good) and _counts(root) == (2, 60, 60)
    assert ingest(root).quarantined == []  # nothing left to quarantine


def test_failed_run_is_recorded_with_its_reason(root: DataRoot, add_run) -> None:
    add_run("failed-empty", n_frames=0, failed=True)
    add_run("ok", seed=2)
    report = ingest(root)
    assert sorted(report.ingested) == ["failed-empty", "ok"]
    rows = Warehouse(root).sql(
        "SELECT scenario_id, status, reason, n_frames FROM scenarios ORDER BY scenario_id"
    ).to_pylist()
    assert rows[0] == {"scenario_id": "failed-empty", "status": "failed",
                       "reason": "test failure", "n_frames": 0}


def test_crash_between_frames_and_commit_leaves_nothing_and_next_ingest_completes(
    root: DataRoot, add_run, monkeypatch: pytest.MonkeyPatch
) -> None:
    for i in range(3):
        add_run(f"crash-{i}", seed=i)

    def killed(*args, **kwargs):
        raise KeyboardInterrupt("killed before the commit")

    with monkeypatch.context() as m:
        m.setattr(PartStore, "commit", killed)
        with pytest.raises(KeyboardInterrupt):
            ingest(root)
    # frames and frame_features parts are on disk, but no run is visible anywhere
    assert any(root.table_dir("frames").rglob("*.parquet"))
    assert _counts(root) == (0, 0, 0)
    wh = Warehouse(root)
    assert wh.sql("SELECT count(*) AS n FROM frame_labels").column("n")[0].as_py() == 0
    orphans = PartStore(root).orphans()
    assert len(orphans) == 2  # one frames part, one frame_features part

    report = ingest(root)
    assert sorted(report.ingested) == ["crash-0", "crash-1", "crash-2"]
    assert sorted(report.orphans_removed) == sorted(root.relative(p) for p in orphans)
    assert _counts(root) == (3, 90, 90)  # complete, and nothing counted twice
    raw = wh.sql("SELECT count(*) AS n FROM frames_parquet").column("n")[0].as_py()
    assert raw == 90


def test_second_writer_is_refused_with_a_clear_error(root: DataRoot, add_run) -> None:
    add_run("locked", seed=1)
    with WriterLock(root.writer_lock):
        with pytest.raises(WarehouseLockedError, match="another process") as err:
            ingest(root)
        assert str(root.writer_lock) in str(err.value)
        assert _counts(root) == (0, 0, 0)
    assert ingest(root).ingested == ["locked"]  # released: the next writer goes ahead


def test_log_layer_reads_what_ingest_skips_without_reading(root: DataRoot, add_run) -> None:
    log = add_run("skip", seed=4)
    ingest(root)
    log.write_bytes(b"not an mcap any more")  # an ingested log is never read again
    report = ingest(root)
    assert report.skipped == 1 and not report.quarantined
    with pytest.raises(Exception, match="skip.mcap"):
        read_run(log)


def _edited(episode, **changes):
    from dataclasses import replace

    episode.spec = replace(episode.spec, **changes)
    return episode


def test_metadata_that_does_not_fit_its_logical_scenario_is_quarantined(
        root: DataRoot, episode_factory, log_writer) -> None:
    from evoeye.scenarios import get_scenario

    space = get_scenario("highway-cut-in")
    genuine = episode_factory("x", seed=5)
    genuine_id = space.scenario_id(np.asarray(genuine.spec.params), genuine.spec.seed)
    genuine = _edited(genuine, scenario_id=genuine_id)
    speed = space.index(space.names[0])
    fast = list(genuine.spec.params)
    fast[speed] = space.high[speed] + 69.5
    bad = {
        "out-of-range": _edited(episode_factory("out-of-range", seed=6), params=tuple(fast)),
        "unknown": _edited(episode_factory("unknown", seed=7), scenario="no-such-scenario"),
        # a forged id: the genuine run's id on another vector, written first
        genuine_id: _edited(episode_factory("forged", seed=8), batch="a-first",
                            scenario_id=genuine_id),
        # an id of the simulator's form, of another scenario: it could shadow that one's run
        "unprotected-intersection-0123456789ab": _edited(
            episode_factory("other", seed=9), scenario_id="unprotected-intersection-0123456789ab"),
    }
    for episode in bad.values():
        log_writer(root, episode)
    forged = root.run_log("highway-cut-in", "a-first", genuine_id)
    assert forged.exists()
    log_writer(root, genuine)
    report = ingest(root)
    reasons = dict(report.quarantined)
    assert report.ingested == [genuine_id] and len(reasons) == 4
    assert "outside" in reasons["runs/highway-cut-in/b000/out-of-range.mcap"]
    assert "unknown logical scenario" in reasons["runs/no-such-scenario/b000/unknown.mcap"]
    assert "does not match" in reasons[f"runs/highway-cut-in/a-first/{genuine_id}.mcap"]
    other = "runs/highway-cut-in/b000/unprotected-intersection-0123456789ab.mcap"
    assert "does not match" in reasons[other]
    assert (root.quarantine / "highway-cut-in" / "a-first" / f"{genuine_id}.mcap").exists()


def test_a_run_of_another_minor_release_is_quarantined(root: DataRoot, episode_factory,
                                                        log_writer) -> None:
    from evoeye import __version__

    major, minor = __version__.split(".")[:2]
    versions = {"newer": f"{int(major) + 1}.{minor}.0", "patch": f"{major}.{minor}.99",
                "synthetic": None}  # the factory's own, not a release's version string
    for name, version in versions.items():
        episode = episode_factory(name, seed=11)
        if version:
            episode.software_version = version
        log_writer(root, episode)
    report = ingest(root)
    reasons = dict(report.quarantined)
    assert sorted(report.ingested) == ["patch", "synthetic"] and len(reasons) == 1
    why = reasons["runs/highway-cut-in/b000/newer.mcap"]
    assert f"written by evoeye {versions['newer']}" in why
    assert f"{major}.{minor}" in why and "docs/warehouse.md" in why


def test_the_ads_profile_is_a_column_and_explain_resimulates_under_it(
        root: DataRoot, episode_factory, log_writer) -> None:
    from dataclasses import replace

    from evoeye.evaluation.explain import pending_runs

    plain = episode_factory("p-default", n_frames=6, seed=1, collision_frame=3)
    firm = episode_factory("p-firm", n_frames=6, seed=2, collision_frame=3)
    firm.spec = replace(firm.spec, ads="firm-yield")
    for ep in (plain, firm):
        log_writer(root, ep)
    ingest(root)
    rows = Warehouse(root).sql("SELECT scenario_id, ads_profile FROM scenarios "
                               "ORDER BY scenario_id").to_pylist()
    assert rows == [{"scenario_id": "p-default", "ads_profile": "default"},
                    {"scenario_id": "p-firm", "ads_profile": "firm-yield"}]
    specs = {s.scenario_id: s.ads for s in pending_runs(root)}
    assert specs == {"p-default": "default", "p-firm": "firm-yield"}


def test_a_world_variants_run_is_left_out_where_it_is(root: DataRoot, episode_factory,
                                                       log_writer) -> None:
    from dataclasses import replace

    from evoeye.evaluation.explain import spec_of

    plain = episode_factory("w-default", n_frames=6, seed=1)
    follower = episode_factory("w-follower", n_frames=6, seed=2)
    follower.spec = replace(follower.spec, world="follower")
    logs = [log_writer(root, ep) for ep in (plain, follower)]
    report = ingest(root)
    assert report.ingested == ["w-default"] and not report.quarantined
    assert report.left_out == ["runs/highway-cut-in/b000/w-follower.mcap"]
    assert logs[1].exists()  # still there, for `evoeye supervise` to read
    assert spec_of(read_run(logs[1], topics=()).metadata).world == "follower"
    assert spec_of(read_run(logs[0], topics=()).metadata).world == "default"
    again = ingest(root)
    assert not again.ingested and again.left_out == report.left_out
