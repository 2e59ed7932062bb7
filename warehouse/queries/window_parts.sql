-- The committed Parquet parts that hold the runs listed in `selected_runs` (a relation with a
-- scenario_id column that the caller registers): a run's frames and frame_features rows sit in
-- the part <ingest_id>.parquet of its partition (evoeye/store/parts.py), committed by the
-- scenarios part of the same name.
SELECT DISTINCT s.logical_scenario, s.batch, s.ingest_id
FROM scenarios AS s
SEMI JOIN selected_runs AS sel ON s.scenario_id = sel.scenario_id
ORDER BY s.logical_scenario, s.batch, s.ingest_id;
