"""A bag without ground truth ingests unlabelled: queryable, never trained, calibrated or measured.

Four runs of logical scenario `external`: the two simulated runs' bags with their ground-truth
topics (labelled) and without (unlabelled). Every path that selects training, validation or
test data — the split macro, select_runs, eligible frames and labels, the windows the monitor
trains, calibrates and is scored on, the dataset statistics — sees the labelled two only, even
when a caller names the unlabelled runs explicitly; the warehouse still holds their frames.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from evoeye.paths import DataRoot
from evoeye.sources.autoware.config import Topics
from evoeye.sources.autoware.importer import import_bags
from evoeye.splits import SPLITS
from evoeye.store import RunFilter, SplitSpec, Warehouse, load_windows, select_runs

T = Topics()
GROUND_TRUTH = {T.ground_truth_objects, T.ground_truth_ego, T.collision}


def _column(root: DataRoot, sql: str, **params) -> list:
    return Warehouse(root).sql(sql, params=params or None).column(0).to_pylist()


@pytest.fixture(scope="module")
def mixed(sim_runs, messages, bag_at, tmp_path_factory) -> tuple[DataRoot, dict[str, str]]:
    base = tmp_path_factory.mktemp("mixed")
    bags = []
    for sid in sorted(sim_runs.logs):
        _, msgs = messages(sid)
        msgs = [m for m in msgs if m[0] < 3_000_000_000]  # 60 frames
        bags.append(bag_at(base / f"{sid}-gt", msgs))
        bags.append(bag_at(base / f"{sid}-none", [m for m in msgs if m[1] not in GROUND_TRUTH]))
    root = DataRoot.resolve(base / "data")
    report = import_bags(root, bags)
    assert report.failed == [] and len(report.ingest[0].ingested) == 4
    return root, report.labels


def test_the_label_source_is_a_column(mixed) -> None:
    root, labels = mixed
    rows = Warehouse(root).sql("SELECT scenario_id, label_source FROM scenarios").to_pylist()
    assert {r["scenario_id"]: r["label_source"] for r in rows} == labels
    assert sorted(labels.values()) == ["ground_truth_objects:" + T.ground_truth_objects] * 2 \
        + ["none"] * 2


def test_unlabelled_runs_are_in_no_split_label_or_window(mixed) -> None:
    root, labels = mixed
    labelled = sorted(s for s, src in labels.items() if src != "none")
    unlabelled = sorted(s for s, src in labels.items() if src == "none")
    # the frames are there to query
    assert _column(root, "SELECT count(DISTINCT scenario_id) FROM frames") == [4]
    # splits, for any shares: all of train + val (+ test) are the labelled runs
    with Warehouse(root).connect() as con:
        for spec in (SplitSpec(), SplitSpec(train_frac=1.0, val_frac=0.0),
                     SplitSpec(train_frac=0.0, val_frac=1.0)):
            chosen = set()
            for split in SPLITS:
                ids = select_runs(con, RunFilter(logical_scenario="external", split=split,
                                                 splits=spec))
                chosen |= set(ids.column("scenario_id").to_pylist())
            assert sorted(chosen) == labelled
    # eligible frames and labels: none of an unlabelled run
    for view in ("eligible_frames", "frame_labels"):
        assert _column(root, f"SELECT DISTINCT scenario_id FROM {view} ORDER BY 1") == labelled
    # the windows a monitor is trained, calibrated and scored on, even when asked by name
    windows = load_windows(root, unlabelled + labelled, context_len=2)
    assert sorted(set(windows.scenario_id)) == labelled and len(windows) > 0
    assert len(load_windows(root, unlabelled)) == 0
    # the dataset statistics count the labelled runs only
    assert sum(_column(root, "SELECT scenarios FROM dataset_stats")) == 2


def test_an_unlabelled_run_keeps_its_frames_and_ages(mixed) -> None:
    root, labels = mixed
    sid = next(s for s, src in labels.items() if src == "none")
    n, collided = Warehouse(root).sql(
        "SELECT count(*), bool_or(gt_ego_collision) FROM frames WHERE scenario_id = $sid",
        params={"sid": sid}).to_pylist()[0].values()
    assert n == 60 and collided is False  # no ground truth: never a collision
    assert Path(root.run_log("external", "autoware", sid)).is_file()  # replayable
