-- The ingest ledger: every committed run and the log it came from (path relative to the root).
SELECT scenario_id, log_path, ingest_id
FROM scenarios_parquet;
