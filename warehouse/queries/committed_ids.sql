-- The ledger rows of some runs: which of the scenario ids $ids are committed, and from which
-- log (path relative to the root). A batch ingest asks it for the runs it is about to commit.
SELECT scenario_id, log_path
FROM scenarios_parquet
WHERE list_contains($ids, scenario_id);
