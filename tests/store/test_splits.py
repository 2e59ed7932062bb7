"""Splits by scenario, never by frame, reproducible from a seed."""

from __future__ import annotations

from dataclasses import asdict

import duckdb
import pytest

from evoeye.paths import DataRoot
from evoeye.store import RunFilter, SplitSpec, Warehouse, ingest, select_runs
from evoeye.store.sqlfiles import view_scripts


def _splits(ids: list[str], rounds: list[int] | None = None, seed: int = 0,
            train: float = 0.5, val: float = 0.125, batches: list[str] | None = None,
            test_batch: str | None = None) -> dict[str, str]:
    """Run the real splits script over a stand-in `scenarios` table of `ids`."""
    con = duckdb.connect()
    con.execute("CREATE TABLE scenarios (scenario_id VARCHAR, logical_scenario VARCHAR, "
                "round INTEGER, batch VARCHAR, label_source VARCHAR)")
    rows = [(i, "s", r, b, "simulator") for i, r, b in zip(ids, rounds or [0] * len(ids),
                                                            batches or ["b0"] * len(ids),
                                                            strict=True)]
    con.executemany("INSERT INTO scenarios VALUES (?, ?, ?, ?, ?)", rows)
    con.execute(dict(view_scripts())["06_splits"])
    result = con.execute("SELECT scenario_id, split FROM scenario_splits(?, ?, ?, "
                         "test_batch := ?)", [seed, train, val, test_batch]).fetchall()
    con.close()
    return dict(result)


IDS = [f"scenario-{i:05d}" for i in range(4000)]


def test_every_scenario_gets_exactly_one_split_in_the_asked_proportions() -> None:
    s = _splits(IDS)
    assert set(s) == set(IDS)
    share = {name: sum(v == name for v in s.values()) / len(IDS) for name in ("train", "val",
                                                                              "test")}
    assert share["train"] == pytest.approx(0.5, abs=0.03)
    assert share["val"] == pytest.approx(0.125, abs=0.02)
    assert share["test"] == pytest.approx(0.375, abs=0.03)


def test_split_is_stable_for_a_seed_and_independent_of_other_runs() -> None:
    s = _splits(IDS[:1000])
    assert _splits(IDS[:1000]) == s
    grown = _splits(IDS)  # adding runs leaves every earlier run where it was
    assert {k: grown[k] for k in s} == s
    other = _splits(IDS[:1000], seed=1)
    assert sum(other[k] != s[k] for k in s) > 300  # another seed is another split


def test_a_test_batch_is_all_test_and_leaves_the_other_runs_where_they_were() -> None:
    batches = ["held" if i % 4 == 0 else "init" for i in range(len(IDS))]
    without = _splits(IDS, batches=batches)
    s = _splits(IDS, batches=batches, test_batch="held")
    held = {i for i, b in zip(IDS, batches, strict=True) if b == "held"}
    assert {s[i] for i in held} == {"test"}
    assert {i: s[i] for i in IDS if i not in held} == {i: without[i] for i in IDS
                                                        if i not in held}
    assert sum(without[i] != "test" for i in held) > 500  # the batch did move runs
    # shares summing to 1: the Test Set is the batch alone
    whole = _splits(IDS, batches=batches, train=0.8, val=0.2, test_batch="held")
    assert {i for i, v in whole.items() if v == "test"} == held
    # a test batch's runs acquired in a campaign round would still train
    assert set(_splits(IDS[:8], rounds=[1] * 8, batches=["held"] * 8,
                       test_batch="held").values()) == {"train"}


def test_runs_acquired_during_evolution_always_train() -> None:
    s = _splits(IDS[:500], rounds=[1 + i % 3 for i in range(500)])
    assert set(s.values()) == {"train"}


def test_warehouse_splits_partition_the_runs(root: DataRoot, add_run) -> None:
    for i in range(12):
        add_run(f"run-{i:02d}", n_frames=2, seed=i)
    ingest(root)
    wh = Warehouse(root)
    rows = wh.sql("SELECT scenario_id, split FROM splits").to_pylist()
    assert sorted(r["scenario_id"] for r in rows) == [f"run-{i:02d}" for i in range(12)]
    con = wh.connect()
    try:
        parts = {
            name: set(select_runs(con, RunFilter(split=name)).column("scenario_id").to_pylist())
            for name in ("train", "val", "test")
        }
        seeded = select_runs(con, RunFilter(split="train", splits=SplitSpec(seed=3)))
    finally:
        con.close()
    assert set.union(*parts.values()) == {r["scenario_id"] for r in rows}
    assert sum(len(p) for p in parts.values()) == 12  # disjoint
    assert parts["train"] == {r["scenario_id"] for r in rows if r["split"] == "train"}
    assert set(seeded.column("scenario_id").to_pylist()) != parts["train"]


def test_a_held_out_batch_is_the_test_split_and_never_initial_data(root: DataRoot,
                                                                     add_run) -> None:
    for i in range(6):
        add_run(f"init-{i}", n_frames=2, seed=i, batch="init")
        add_run(f"held-{i}", n_frames=2, seed=10 + i, batch="held")
    add_run("acquired", n_frames=2, seed=30, batch="campaign", round=1)
    ingest(root)
    splits = SplitSpec(train_frac=0.7, val_frac=0.3, test_batch="held")
    wh = Warehouse(root)
    con = wh.connect()
    try:
        test = select_runs(con, RunFilter(split="test", splits=splits))
    finally:
        con.close()
    assert sorted(test.column("scenario_id").to_pylist()) == [f"held-{i}" for i in range(6)]
    initial = wh.query("initial_records", scenario="highway-cut-in", **asdict(splits))
    assert initial.num_rows > 0
    assert not any(i.startswith("held") for i in initial.column("scenario_id").to_pylist())
    stats = {r["split"]: r["scenarios"] for r in wh.query(
        "dataset_stats", horizon_s=3.0, **asdict(splits)).to_pylist()}
    assert stats["test"] == 6 and stats["train"] + stats["val"] == 7  # with the acquired run
    initial = {r["split"]: r["scenarios"] for r in wh.query(
        "initial_split_stats", logical_scenario="highway-cut-in", horizon_s=3.0,
        **asdict(splits)).to_pylist()}
    assert initial["test"] == 6 and initial["train"] + initial["val"] == 6


def test_bad_split_arguments_are_refused() -> None:
    with pytest.raises(ValueError, match="split must be"):
        RunFilter(split="holdout")
    with pytest.raises(ValueError, match="sum <= 1"):
        SplitSpec(train_frac=0.9, val_frac=0.2)
    with pytest.raises(ValueError, match="not a plain name"):
        SplitSpec(test_batch="../elsewhere")
