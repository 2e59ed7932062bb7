-- monitor_scores: one row per frame scored by one monitor version (the evaluation harness's
-- output, `evoeye evaluate`). score is the monitor's risk r_t in [0, 1] for the window ending
-- at `frame` (higher = riskier). Append-only Parquet parts under warehouse/monitor_scores/,
-- one part per evaluation; a (monitor_version, scenario_id) pair is written at most once, so
-- re-running an evaluation adds nothing. Labels are not stored: join frame_labels_h(h) on
-- (scenario_id, frame) for the horizon you want.
CREATE TABLE monitor_scores (
    monitor_name      VARCHAR  NOT NULL,  -- fusion / ttc / rss / aem / …
    monitor_version   VARCHAR  NOT NULL,  -- the scored artefact (Monitor.version)
    logical_scenario  VARCHAR  NOT NULL,
    scenario_id       VARCHAR  NOT NULL,
    frame             INTEGER  NOT NULL,  -- frame index in the run (frames.frame)
    t_s               DOUBLE   NOT NULL,  -- tau_t of the frame
    score             FLOAT    NOT NULL,  -- risk in [0, 1]
    evaluation_id     VARCHAR  NOT NULL,  -- the part (one evaluation) the row was written in
    scored_at         TIMESTAMP WITH TIME ZONE NOT NULL
);
