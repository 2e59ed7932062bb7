-- campaign_rounds: one row per finished acquisition round of an evolution campaign (Algorithm 1).
-- Round 0 is the start: the initial monitor G_0 and no acquired run. Row r names the monitor
-- G_r trained after round r and the runs that round acquired, in acquisition order, so the
-- campaign's records D_r are D_init followed by the scenario_ids of rounds 1 .. r. A resumed
-- campaign starts from its last row. (campaign_id, round) is written at most once.
CREATE TABLE campaign_rounds (
    campaign_id       VARCHAR   NOT NULL,  -- stable id of (scenario, strategy, seed, G_0, D_init…)
    logical_scenario  VARCHAR   NOT NULL,
    strategy          VARCHAR   NOT NULL,  -- acquisition strategy name
    seed              BIGINT    NOT NULL,
    round             INTEGER   NOT NULL,  -- r; 0 = the start
    monitor_version   VARCHAR   NOT NULL,  -- G_r
    scenario_ids      VARCHAR[] NOT NULL,  -- runs acquired in this round, in acquisition order
    n_records         INTEGER   NOT NULL,  -- runs acquired so far (rounds 1 .. r)
    simulated_s       DOUBLE    NOT NULL,  -- simulated time spent so far (the budget charged)
    train_s           DOUBLE    NOT NULL,  -- wall time of this round's monitor update
    metrics           VARCHAR   NOT NULL,  -- JSON: G_r on the test / hard set; '' if not assessed
    finished_at       TIMESTAMP WITH TIME ZONE NOT NULL
);
