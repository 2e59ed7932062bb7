-- frame_features: one row per row of frames: the runtime signals of the frame turned into the
-- fixed-size monitor inputs of evoeye/store/features.py (ego frame of the ADS's localization,
-- obstacles nearest first). Derived from runtime signals only: no ground truth enters.
-- Every array is flattened row-major to a fixed length set by features.FEATURES (n = 8
-- obstacles, K = 10 predicted points, P = 11 planned points); masks are stored as counts
-- because slots fill from the front (mask[i] = i < count).
-- logical_scenario and batch are hive partition keys (folder names, not stored in the files).
CREATE TABLE frame_features (
    scenario_id    VARCHAR  NOT NULL,
    frame          INTEGER  NOT NULL,
    perception     FLOAT[]  NOT NULL,  -- (n, 9): dx_m dy_m cos_dheading sin_dheading dvx_mps
                                       --          dvy_mps length_m width_m confidence
    n_perceived    INTEGER  NOT NULL,  -- obstacle slots filled
    prediction     FLOAT[]  NOT NULL,  -- (n, K, 2): dx_m dy_m of each predicted point
    n_predicted    INTEGER  NOT NULL,  -- prediction slots filled
    plan           FLOAT[]  NOT NULL,  -- (P, 7): t_rel_s dx_m dy_m cos_dheading sin_dheading
                                       --          speed_mps accel_mps2
    n_plan_points  INTEGER  NOT NULL,  -- planned points present
    plan_info      FLOAT[]  NOT NULL,  -- (6): target_speed_mps, one-hot decision
    control        FLOAT[]  NOT NULL,  -- (6): throttle brake steering_rad accel_cmd_mps2
                                       --      ego_speed_mps ego_accel_mps2
    ingest_id      VARCHAR  NOT NULL,
    logical_scenario VARCHAR NOT NULL, -- partition key
    batch          VARCHAR  NOT NULL   -- partition key
);
