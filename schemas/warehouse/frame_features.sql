-- frame_features: one row per row of frames: the runtime signals of the frame turned into the
-- fixed-size monitor inputs of evoeye/store/features.py (ego frame of the ADS's localization,
-- obstacles nearest first). Derived from runtime signals only: no ground truth enters.
-- Every array is one BLOB per frame: its float32 values flattened row-major, little-endian
-- (4 bytes each, a fixed count set by features.FEATURES: n = 8 obstacles, K = 10 predicted
-- points, P = 11 planned points), written as Parquet FIXED_LEN_BYTE_ARRAY; in SQL,
-- float32s(perception) gives them as FLOAT[] (warehouse/views/03_frame_features.sql). Masks
-- are stored as counts because slots fill from the front (mask[i] = i < count).
-- A part's rows are the rows of the frames part of the same name, in the same order.
-- logical_scenario and batch are hive partition keys (folder names, not stored in the files).
CREATE TABLE frame_features (
    scenario_id    VARCHAR  NOT NULL,
    frame          INTEGER  NOT NULL,
    perception     BLOB     NOT NULL,  -- (n, 9): dx_m dy_m cos_dheading sin_dheading dvx_mps
                                       --          dvy_mps length_m width_m confidence
    n_perceived    INTEGER  NOT NULL,  -- obstacle slots filled
    prediction     BLOB     NOT NULL,  -- (n, K, 2): dx_m dy_m of each predicted point
    n_predicted    INTEGER  NOT NULL,  -- prediction slots filled
    plan           BLOB     NOT NULL,  -- (P, 7): t_rel_s dx_m dy_m cos_dheading sin_dheading
                                       --          speed_mps accel_mps2
    n_plan_points  INTEGER  NOT NULL,  -- planned points present
    plan_info      BLOB     NOT NULL,  -- (6): target_speed_mps, one-hot decision
    control        BLOB     NOT NULL,  -- (6): throttle brake steering_rad accel_cmd_mps2
                                       --      ego_speed_mps ego_accel_mps2
    ingest_id      VARCHAR  NOT NULL,
    logical_scenario VARCHAR NOT NULL, -- partition key
    batch          VARCHAR  NOT NULL   -- partition key
);
