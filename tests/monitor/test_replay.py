"""Replay: the copy has every original record, one risk message per frame, alarm markers."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from jsonschema import Draft202012Validator
from mcap.reader import make_reader
from typer.testing import CliRunner

import evoeye.cli.monitor  # noqa: F401  (registers the commands)
from evoeye.cli.app import app
from evoeye.cli.errors import ExitCode
from evoeye.log import TOPICS, read_run
from evoeye.log.channels import load_schema
from evoeye.monitor.registry import load_monitor
from evoeye.monitor.replay import RISK_SCHEMA_FILE, RISK_TOPIC, VIZ_TOPIC, replay
from evoeye.store import load_windows


def records(path: Path) -> tuple[list[tuple[str, int, bytes]], dict, list]:
    """(messages as (topic, log time, data), metadata by name, attachment names)."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        msgs = [(c.topic, m.log_time, m.data) for _, c, m in reader.iter_messages()]
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        attachments = [a.name for a in reader.iter_attachments()]
    return msgs, meta, attachments


@pytest.fixture(scope="module")
def replayed(tiny, trained, tmp_path_factory):
    sid = tiny.ids["val"][0]  # a colliding run
    out = tmp_path_factory.mktemp("replay") / "run.risk.mcap"
    report = replay(tiny.logs[sid], load_monitor(tiny.root, trained), out, consecutive=1)
    return sid, report


def test_copy_keeps_every_original_record(tiny, replayed) -> None:
    sid, report = replayed
    original, meta, attachments = records(tiny.logs[sid])
    copy, meta2, attachments2 = records(report.out)
    assert meta2 == meta and attachments2 == attachments
    ours = {RISK_TOPIC, VIZ_TOPIC}
    assert Counter(m for m in copy if m[0] not in ours) == Counter(original)
    assert read_run(report.out).metadata == read_run(tiny.logs[sid]).metadata


def test_one_risk_message_per_frame_with_alarms_above_the_threshold(
    tiny, trained, replayed
) -> None:
    sid, report = replayed
    run = read_run(report.out)
    risk = [m for _, m in run.messages(RISK_TOPIC)]
    frame_times = [m["t_s"] for _, m in run.messages(TOPICS.localization)]
    assert report.frames == len(risk) == len(frame_times) == 40
    assert [r["t_s"] for r in risk] == frame_times
    assert run.log_times_ns(RISK_TOPIC) == run.log_times_ns(TOPICS.localization)
    validator = Draft202012Validator(load_schema(RISK_SCHEMA_FILE))
    for r in risk:
        validator.validate(r)
    monitor = load_monitor(tiny.root, trained)
    scores = np.array([r["score"] for r in risk])
    batch = monitor.score(load_windows(tiny.root, [sid], context_len=5,
                                       horizon_s=tiny.horizon_s))
    # the replay scores every frame of the log; the warehouse windows stop before a collision
    np.testing.assert_allclose(scores[:len(batch)], batch, rtol=0, atol=1e-5)
    threshold = monitor.thresholds.at(0.05)
    assert {r["threshold"] for r in risk} == {threshold}
    assert {r["monitor_version"] for r in risk} == {trained}
    assert [r["alarm"] for r in risk] == (scores > threshold).tolist()
    assert report.alarm_frames == int((scores > threshold).sum()) > 0


def test_scene_markers_show_the_alarm(replayed) -> None:
    _, report = replayed
    run = read_run(report.out)
    risk = [m for _, m in run.messages(RISK_TOPIC)]
    viz = [m for _, m in run.messages(VIZ_TOPIC)]
    assert len(viz) == len(risk)
    validator = Draft202012Validator(load_schema("scene_update.v1.json"))
    for r, v in zip(risk, viz, strict=True):
        validator.validate(v)
        ids = {e["id"] for e in v["entities"]}
        assert ("monitor/alarm" in ids) == r["alarm"]
        text = next(e for e in v["entities"] if e["id"] == "monitor/risk")["texts"][0]["text"]
        assert f"{r['score']:.2f}" in text and ("ALARM" in text) == r["alarm"]
    assert run.schema_ids[VIZ_TOPIC] == run.schema_ids[TOPICS.scene]  # foxglove.SceneUpdate


def test_replaying_a_replay_replaces_the_monitor_channels(tiny, trained, replayed,
                                                          tmp_path) -> None:
    _, report = replayed
    again = replay(report.out, load_monitor(tiny.root, trained), tmp_path / "twice.mcap",
                   consecutive=3)
    msgs, _, _ = records(again.out)
    counts = Counter(topic for topic, _, _ in msgs)
    assert counts[RISK_TOPIC] == counts[VIZ_TOPIC] == 40
    assert again.alarm_frames <= report.alarm_frames
    with pytest.raises(ValueError, match="overwrite"):
        replay(report.out, load_monitor(tiny.root, trained), report.out)


def test_cli_replay_and_export(tiny, trained, tmp_path) -> None:
    runner = CliRunner()
    log = tiny.logs[tiny.ids["val"][0]]
    out = tmp_path / "cli.mcap"
    result = runner.invoke(app, ["replay", str(log), "--monitor", trained,
                                 "--root", str(tiny.root.path), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "40 frames" in result.output and out.exists()
    assert "collision at t = " in result.output  # the val run collides
    result = runner.invoke(app, ["export", "--monitor", trained, "--root", str(tiny.root.path),
                                 "--out", str(tmp_path / "m.onnx")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "m.onnx").stat().st_size > 10_000
    result = runner.invoke(app, ["replay", str(log), "--monitor", "fusion-missing",
                                 "--root", str(tiny.root.path)])
    assert result.exit_code == ExitCode.USER_ERROR and "no monitor version" in result.output
    assert "hint: list the versions" in result.output and "Traceback" not in result.output


def test_cli_replay_writes_to_replays_and_warns_on_another_scenario(tiny, trained) -> None:
    import shutil

    import orjson

    from evoeye.store import ingest

    runner = CliRunner(env={"COLUMNS": "200"})
    log = tiny.logs[tiny.ids["val"][0]]
    result = runner.invoke(app, ["replay", str(log), "--monitor", trained,
                                 "--root", str(tiny.root.path)])
    assert result.exit_code == 0, result.output
    copy = tiny.root.replays / f"{log.stem}.{trained}.risk.mcap"
    assert copy.exists() and not list(tiny.root.runs.rglob("*.risk.mcap"))
    assert "warning" not in result.output
    assert not ingest(tiny.root).duplicates  # the replay is not a run log
    other = tiny.root.monitors / "fusion-elsewhere0"
    shutil.copytree(tiny.root.monitors / trained, other)
    card = orjson.loads((other / "card.json").read_bytes())
    card["logical_scenario"] = "unprotected-intersection"
    (other / "card.json").write_bytes(orjson.dumps(card))
    result = runner.invoke(app, ["replay", str(log), "--monitor", other.name,
                                 "--root", str(tiny.root.path)])
    assert result.exit_code == 0, result.output
    assert "warning:" in result.output and "trained on unprotected-intersection" in result.output


def test_the_report_knows_when_the_run_collided_and_how_early_it_warned(tiny, replayed) -> None:
    sid, report = replayed
    meta = read_run(tiny.logs[sid], topics=()).metadata
    assert meta["collided"] and report.collision_t_s == pytest.approx(meta["collision_time_s"])
    if report.warning_t_s is not None:
        assert report.lead_s == pytest.approx(report.collision_t_s - report.warning_t_s)
        assert report.words().endswith(f"{report.lead_s:.2f} s before it")
    else:
        assert report.words().endswith("no alarm before it (missed)")


@pytest.mark.parametrize(("first_alarm", "collision", "words"), [
    (1.5, 4.0, "collision at t = 4.00 s; first alarm at t = 1.50 s, 2.50 s before it"),
    (4.2, 4.0, "collision at t = 4.00 s; no alarm before it (missed)"),
    (None, 4.0, "collision at t = 4.00 s; no alarm before it (missed)"),
    (3.0, None, "no collision; a false alarm at t = 3.00 s"),
    (None, None, "no collision; no alarm"),
])
def test_the_outcome_in_words(first_alarm, collision, words) -> None:
    from evoeye.monitor.replay import ReplayReport

    report = ReplayReport(Path("x"), 100, 3, first_alarm, 0.5, collision)
    assert report.words() == words
    if "before it" in words and "missed" not in words:
        assert report.lead_s == pytest.approx(collision - first_alarm)
    else:
        assert report.lead_s is None
