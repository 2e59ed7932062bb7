-- frames: the frames of committed runs only.
-- A run's frames are written before its scenarios row; rows whose (scenario_id, ingest_id) has no
-- committed scenarios row belong to an ingest that died in between and stay invisible here.
CREATE OR REPLACE VIEW frames AS
SELECT f.*
FROM frames_parquet AS f
SEMI JOIN scenarios AS s
    ON f.scenario_id = s.scenario_id AND f.ingest_id = s.ingest_id;
