"""Splits by scenario, never by frame, reproducible from a seed."""

from __future__ import annotations

import duckdb
import pytest

from evoeye.paths import DataRoot
from evoeye.store import RunFilter, SplitSpec, Warehouse, ingest, select_runs
from evoeye.store.sqlfiles import view_scripts


def _splits(ids: list[str], rounds: list[int] | None = None, seed: int = 0,
            train: float = 0.5, val: float = 0.125) -> dict[str, str]:
    """Run the real splits script over a stand-in `scenarios` table of `ids`."""
    con = duckdb.connect()
    con.execute("CREATE TABLE scenarios (scenario_id VARCHAR, logical_scenario VARCHAR, "
                "round INTEGER)")
    rows = [(i, "s", r) for i, r in zip(ids, rounds or [0] * len(ids), strict=True)]
    con.executemany("INSERT INTO scenarios VALUES (?, ?, ?)", rows)
    con.execute(dict(view_scripts())["06_splits"])
    result = con.execute("SELECT scenario_id, split FROM scenario_splits(?, ?, ?)",
                         [seed, train, val]).fetchall()
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


def test_bad_split_arguments_are_refused() -> None:
    with pytest.raises(ValueError, match="split must be"):
        RunFilter(split="holdout")
    with pytest.raises(ValueError, match="sum <= 1"):
        SplitSpec(train_frac=0.9, val_frac=0.2)
