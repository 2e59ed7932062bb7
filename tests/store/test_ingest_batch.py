"""Ingesting one batch folder: from the caller's conversion, as a writer of its own keys."""

from __future__ import annotations

import shutil

import pytest

from evoeye.paths import DataRoot
from evoeye.store import Warehouse, ingest
from evoeye.store.ingest import ingest_batch
from evoeye.store.lock import key_lock
from evoeye.store.log_windows import read_logged_run
from evoeye.store.parts import PartStore

HIGHWAY = "highway-cut-in"


def rows(root: DataRoot, table: str) -> list[dict]:
    """Every row of a table but where it was written (part names, times)."""
    skip = {"ingest_id", "ingested_at", "log_path"}
    t = Warehouse(root).sql(f"SELECT * FROM {table} ORDER BY scenario_id"
                            + (", frame" if table != "scenarios" else ""))
    return [{k: v for k, v in r.items() if k not in skip} for r in t.to_pylist()]


def test_a_converted_run_is_ingested_without_reading_its_log_again(root: DataRoot, add_run,
                                                                     tmp_path) -> None:
    log = add_run("conv", n_frames=30, collision_frame=20, seed=4, batch="evo-a")
    reference = DataRoot.resolve(tmp_path / "reference")
    shutil.copytree(root.path, reference.path)
    ingest(reference)  # the same log, read by a full ingest
    run = read_logged_run(log, context_len=5, horizon_s=1.0)
    log.write_bytes(b"not an mcap any more")  # the conversion is what gets written
    report = ingest_batch(root, (HIGHWAY, "evo-a"), [run])
    assert report.ingested == ["conv"] and not report.quarantined
    for table in ("scenarios", "frames", "frame_features"):
        assert rows(root, table) == rows(reference, table), table
    assert not root.duckdb_file.exists()  # the catalog file is the full writers'
    assert ingest_batch(root, (HIGHWAY, "evo-a")).skipped == 1  # nothing twice


def test_a_batch_ingest_takes_its_folder_only_and_its_own_orphans(root: DataRoot, add_run,
                                                                    monkeypatch) -> None:
    add_run("mine", seed=1, batch="evo-a")
    add_run("other", seed=2, batch="evo-b")
    store = PartStore(root)

    def killed(*args, **kwargs):
        raise KeyboardInterrupt("killed before the commit")

    with monkeypatch.context() as m:  # both batches leave a killed ingest's parts behind
        m.setattr(PartStore, "commit", killed)
        for batch in ("evo-a", "evo-b"):
            with pytest.raises(KeyboardInterrupt):
                ingest_batch(root, (HIGHWAY, batch))
    theirs = store.orphans((HIGHWAY, "evo-b"))
    assert len(store.orphans()) == 4 and len(theirs) == 2
    report = ingest_batch(root, (HIGHWAY, "evo-a"))
    assert report.ingested == ["mine"] and len(report.orphans_removed) == 2
    assert store.orphans() == theirs  # another batch's parts are its own business


def test_a_run_committed_by_another_batch_is_a_duplicate(root: DataRoot, add_run) -> None:
    add_run("same", seed=3, batch="evo-a")
    add_run("same", seed=3, batch="evo-b")  # the same run acquired by two campaigns
    assert ingest_batch(root, (HIGHWAY, "evo-a")).ingested == ["same"]
    report = ingest_batch(root, (HIGHWAY, "evo-b"))
    assert report.ingested == [] and report.duplicates == [
        f"runs/{HIGHWAY}/evo-b/same.mcap"]
    assert [r["scenario_id"] for r in rows(root, "scenarios")] == ["same"]


def test_batch_ingests_do_not_wait_for_writers_of_other_keys(root: DataRoot, add_run) -> None:
    add_run("free", seed=5, batch="evo-a")
    with key_lock(root, "feedback", ["fusion-x"]):  # e.g. another campaign storing feedback
        assert ingest_batch(root, (HIGHWAY, "evo-a")).ingested == ["free"]


def test_a_batch_ingest_whose_keys_share_a_stripe_does_not_wait_for_itself(
        root: DataRoot, add_run, monkeypatch) -> None:
    import evoeye.store.lock as lock

    monkeypatch.setattr(lock, "STRIPES", 1)  # every key in one stripe: the batch's and its runs'
    add_run("one", seed=6, batch="evo-a")
    add_run("two", seed=7, batch="evo-a")
    held = []
    real = lock.WriterLock.__enter__

    def enter(self):
        assert not (self.path in held and not self.shared), f"{self.path} taken twice"
        held.append(self.path)
        return real(self)

    monkeypatch.setattr(lock.WriterLock, "__enter__", enter)
    assert ingest_batch(root, (HIGHWAY, "evo-a")).ingested == ["one", "two"]
