"""The parts' layout: frame_features arrays as float32 bytes, readable in SQL; older layouts
are refused with the fix, never read as something else."""

from __future__ import annotations

import shutil

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from evoeye.cli.errors import explain
from evoeye.paths import DataRoot
from evoeye.store import Warehouse, ingest, load_windows
from evoeye.store.features import STORED, unpack
from evoeye.store.log_windows import read_logged_run
from evoeye.store.parts import PartStore
from evoeye.store.schema import LAYOUT_KEY, LAYOUT_VERSION, TABLES, WarehouseLayoutError


def _part(root: DataRoot, table: str):
    return next(root.table_dir(table).rglob("*.parquet"))


def test_parts_hold_exactly_the_floats_ingest_computed(root: DataRoot, add_run) -> None:
    log = add_run("r", n_frames=9, seed=3, n_obstacles=5)
    ingest(root)
    computed = read_logged_run(log, context_len=1, horizon_s=3.0).features
    part = pq.read_table(_part(root, "frame_features"), partitioning=None)
    assert part.schema.metadata[LAYOUT_KEY] == str(LAYOUT_VERSION).encode()
    stored = unpack(part)
    for name, arr in computed.arrays().items():
        assert getattr(stored, name).dtype == arr.dtype
        np.testing.assert_array_equal(getattr(stored, name), arr, err_msg=name)
    for name, _, _ in STORED:  # Parquet FIXED_LEN_BYTE_ARRAY, the floats' bytes
        assert part.schema.field(name).type == pa.binary(getattr(computed, name)[0].nbytes)
        in_sql = Warehouse(root).sql(f"SELECT float32s({name}) AS v FROM frame_features "
                                     "ORDER BY frame").column("v").to_pylist()
        np.testing.assert_array_equal(np.array(in_sql, np.float32),
                                      getattr(computed, name).reshape(9, -1), err_msg=name)


def test_float32s_reads_every_float_bit_for_bit(root: DataRoot) -> None:
    values = np.array([0.0, -0.0, 1.5, -2.25e-3, 3.4028235e38, 1e-45, -1.1754942e-38, np.inf,
                       -np.inf, 1 / 3], np.float32)
    got = Warehouse(root).sql("SELECT float32s($b) AS v", {"b": values.tobytes()})
    floats = np.array(got.column("v")[0].as_py(), np.float32)
    np.testing.assert_array_equal(floats.view(np.uint32), values.view(np.uint32))


@pytest.fixture
def old(root: DataRoot, add_run, as_layout_1) -> DataRoot:
    """A warehouse as evoeye <= 0.4.0 left it: float lists, no layout key in any part."""
    add_run("a", n_frames=6, seed=1)
    add_run("b", n_frames=6, collision_frame=4, seed=2)
    ingest(root)
    for table in TABLES:
        for path in root.table_dir(table).rglob("*.parquet"):
            if table == "frame_features":
                as_layout_1(path)
            else:
                data = pq.read_table(path, partitioning=None)
                pq.write_table(data.replace_schema_metadata(None), path)
    return root


def test_an_old_warehouse_is_refused_with_the_fix(old: DataRoot, add_run) -> None:
    for read in (lambda: Warehouse(old).sql("SELECT count(*) FROM scenarios"),
                 lambda: load_windows(old)):
        refused = f"layout 1; this evoeye reads layout {LAYOUT_VERSION}.* re-ingest"
        with pytest.raises(WarehouseLayoutError, match=refused):
            read()
    add_run("c", n_frames=6, seed=3)
    before = sorted(old.warehouse.rglob("*.parquet"))
    with pytest.raises(WarehouseLayoutError) as refused:
        ingest(old)
    assert sorted(old.warehouse.rglob("*.parquet")) == before  # nothing added to it
    assert "re-ingest" in explain(refused.value).hint  # the CLI's one line and hint


def test_following_the_fix_gives_a_warehouse_of_this_layout(old: DataRoot) -> None:
    for table in TABLES:  # as the message says: those folders aside, ingest again
        shutil.move(old.table_dir(table), old.path / f"old-{table}")
    report = ingest(old)
    assert sorted(report.ingested) == ["a", "b"]
    PartStore(old).check_layout()
    assert len(load_windows(old, context_len=2)) == 6 + 4


@pytest.fixture
def layout_4(root: DataRoot, add_run) -> DataRoot:
    """A warehouse as layout 4 left it: the actor ids as INTEGER columns."""
    add_run("a", n_frames=6, seed=1)
    add_run("b", n_frames=6, collision_frame=4, seed=2)
    ingest(root)
    for table in TABLES:
        for path in root.table_dir(table).rglob("*.parquet"):
            data = pq.read_table(path, partitioning=None)
            for name in ("other_actor", "gt_collision_actor"):
                if name in data.column_names:
                    i = data.column_names.index(name)
                    data = data.set_column(i, pa.field(name, pa.int32()),
                                           data.column(name).cast(pa.int32()))
            pq.write_table(data.replace_schema_metadata({LAYOUT_KEY: b"4"}), path)
    return root


def test_a_layout_4_warehouse_is_migrated_in_place_by_ingest(layout_4: DataRoot,
                                                             add_run) -> None:
    root = layout_4
    with pytest.raises(WarehouseLayoutError, match="layout 4; .* migrate: run `evoeye ingest`"):
        Warehouse(root).sql("SELECT count(*) FROM scenarios")
    rows = {t: pq.read_table(root.table_dir(t), partitioning=None).sort_by("scenario_id")
            .to_pylist() for t in ("scenarios", "frames")}
    add_run("c", n_frames=6, seed=3)
    report = ingest(root)
    assert len(report.migrated) == len(TABLES) and report.ingested == ["c"]  # a part each
    PartStore(root).check_layout()
    for t in ("scenarios", "frames"):
        part = next(p for p in root.table_dir(t).rglob("*.parquet")
                    if "c" not in pq.read_table(p, columns=["scenario_id"], partitioning=None)
                    .column("scenario_id").to_pylist())
        migrated = pq.read_table(part, partitioning=None)
        actor = "other_actor" if t == "scenarios" else "gt_collision_actor"
        assert migrated.schema.field(actor).type == pa.int64()
        assert migrated.sort_by("scenario_id").to_pylist() == rows[t]  # every value kept
    assert Warehouse(root).sql("SELECT count(*) AS n FROM scenarios").column("n")[0].as_py() == 3
    assert ingest(root).migrated == []  # once only
