-- scenarios: the committed runs, one row per scenario id.
-- Reads scenarios_parquet (every Parquet part of the table, created by evoeye over
-- warehouse/scenarios/logical_scenario=*/batch=*/*.parquet). The ingester never commits a
-- scenario twice; should two parts ever hold one, the first commit wins.
CREATE OR REPLACE VIEW scenarios AS
SELECT *
FROM scenarios_parquet
QUALIFY row_number() OVER (PARTITION BY scenario_id ORDER BY ingested_at, ingest_id) = 1;
