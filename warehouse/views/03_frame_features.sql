-- frame_features: the monitor inputs of the frames of committed runs (same visibility rule as
-- frames: a part is visible once its scenarios row is committed with the same ingest_id).
CREATE OR REPLACE VIEW frame_features AS
SELECT x.*
FROM frame_features_parquet AS x
SEMI JOIN scenarios AS s
    ON x.scenario_id = s.scenario_id AND x.ingest_id = s.ingest_id;
