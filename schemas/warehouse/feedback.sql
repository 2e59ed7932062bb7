-- feedback: monitor-oriented feedback f_r(x) of one run under one monitor version (paper §IV-C):
-- the mean |ŷ − y| over the run's runtime contexts. Written by the evolution campaign after every
-- monitor update (the refresh of Algorithm 1, line 13) and for each round's new records.
-- Append-only Parquet parts under warehouse/feedback/; a (monitor_version, feedback_mode,
-- scenario_id) triple is written at most once, so a resumed campaign adds nothing it already
-- stored.
CREATE TABLE feedback (
    logical_scenario  VARCHAR  NOT NULL,
    scenario_id       VARCHAR  NOT NULL,
    monitor_version   VARCHAR  NOT NULL,  -- G_r that scored the run
    feedback_mode     VARCHAR  NOT NULL,  -- ŷ as G_r scores it ('raw') or 'prior-corrected', or
                                          -- 'disagreement-k<K>[-prior-corrected]': the spread of
                                          -- G_r's committee's scores (table committee)
    feedback          DOUBLE   NOT NULL,  -- f_r(x) in [0, 1]
    n_contexts        INTEGER  NOT NULL,  -- windows averaged
    part_id           VARCHAR  NOT NULL,  -- the part the row was written in
    written_at        TIMESTAMP WITH TIME ZONE NOT NULL
);
