-- scenarios: one row per ingested run (the scenario record's x and outcome; paper §III).
-- The single source of truth for the table's columns: evoeye derives the Parquet schema from
-- this statement, and a contract test checks every written file against it.
-- logical_scenario and batch are hive partition keys: they live in the folder names
-- (logical_scenario=…/batch=…/) and not inside the Parquet files.
-- A run is visible once its row is here: the row is committed after the run's frames.
CREATE TABLE scenarios (
    scenario_id       VARCHAR   NOT NULL,  -- stable id of (logical scenario, params, seed)
    param_names       VARCHAR[] NOT NULL,  -- parameter names, in vector order
    params            DOUBLE[]  NOT NULL,  -- the concrete scenario vector x
    seed              BIGINT    NOT NULL,  -- simulation seed
    source            VARCHAR   NOT NULL,  -- how x was acquired: initial/uniform/evoeye/avfuzzer/…
    round             INTEGER   NOT NULL,  -- acquisition round (0 = initial data)
    ads_profile       VARCHAR   NOT NULL,  -- the ADS profile that drove the ego ('default', …)
    software_version  VARCHAR   NOT NULL,  -- ADS + simulator version that produced the run
    rate_hz           DOUBLE    NOT NULL,  -- frame rate of the runtime signals
    status            VARCHAR   NOT NULL,  -- 'ok', or 'failed' when the run could not finish
    reason            VARCHAR   NOT NULL,  -- why it failed; '' when ok
    collided          BOOLEAN   NOT NULL,  -- a violation scenario (Definition 1)
    collision_time_s  DOUBLE,              -- tau_col: first frame time with an ego collision
    other_actor       BIGINT,              -- actor of the first ego collision (64-bit: a
                                           -- UUID-derived id of another stack)
    duration_s        DOUBLE    NOT NULL,  -- simulated time
    min_distance_m    DOUBLE,              -- min ego-actor footprint distance over the run
    label_source      VARCHAR   NOT NULL,  -- what labelled collisions: 'simulator', a recorded
                                           -- ground truth ('ground_truth_objects:<topic>',
                                           -- 'collision_topic:<topic>'), or 'none' (unlabelled:
                                           -- never in a split, a label, a window or a metric)
    n_frames          INTEGER   NOT NULL,  -- rows of this run in frames
    log_path          VARCHAR   NOT NULL,  -- the MCAP log, relative to the data root
    ingest_id         VARCHAR   NOT NULL,  -- the Parquet part this run was committed in
    ingested_at       TIMESTAMP WITH TIME ZONE NOT NULL,
    logical_scenario  VARCHAR   NOT NULL,  -- partition key
    batch             VARCHAR   NOT NULL   -- partition key
);
