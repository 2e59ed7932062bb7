-- frames: one row per frame (20 Hz) per run.
-- Runtime signals M(x), the only columns a monitor may read, are prefixed by ADS module:
--   loc_  localization (the ego's own estimate)     obs_  perception (one list entry per obstacle)
--   pred_ prediction (n obstacles x K points)       plan_ planning (P trajectory points)
--   ctrl_ control command                           age_  each module message's age (imports)
-- Ground truth O(x) of the ego is prefixed gt_: evaluation and labels only, never monitor input.
-- In a run of label_source 'none' (scenarios) gt_ holds the ego's own estimate and no collision:
-- such a run is never labelled (views eligible_frames, scenario_splits).
-- World frame, SI units. Per-point arrays are 32-bit floats (the monitor's dtype; sub-mm at km).
-- logical_scenario and batch are hive partition keys (folder names, not stored in the files).
-- Rows are visible only for runs whose scenarios row is committed with the same ingest_id.
CREATE TABLE frames (
    scenario_id            VARCHAR  NOT NULL,
    frame                  INTEGER  NOT NULL,  -- index in the run, 0 .. n_frames-1
    t_s                    DOUBLE   NOT NULL,  -- tau_t, simulation time of the frame
    -- localization
    loc_x_m                DOUBLE,
    loc_y_m                DOUBLE,
    loc_heading_rad        DOUBLE,
    loc_speed_mps          DOUBLE,
    loc_accel_mps2         DOUBLE,
    -- perception: tracked obstacles (n per frame)
    obs_track_id           BIGINT[],
    obs_class              VARCHAR[],
    obs_x_m                FLOAT[],
    obs_y_m                FLOAT[],
    obs_heading_rad        FLOAT[],
    obs_vx_mps             FLOAT[],
    obs_vy_mps             FLOAT[],
    obs_length_m           FLOAT[],
    obs_width_m            FLOAT[],
    obs_confidence         FLOAT[],
    -- prediction: point k of row i (an obstacle's mode) is at t_s + (k+1) * pred_dt_s
    pred_dt_s              DOUBLE,
    pred_track_id          BIGINT[],
    pred_model             VARCHAR[],          -- one row per (obstacle, mode), most probable first
    pred_mode_prob         FLOAT[],
    pred_length_m          FLOAT[],
    pred_width_m           FLOAT[],
    pred_x_m               FLOAT[][],          -- (n, K)
    pred_y_m               FLOAT[][],          -- (n, K)
    -- planning: the committed ego trajectory, point j at t_s + plan_t_rel_s[j]
    plan_decision          VARCHAR,
    plan_target_speed_mps  DOUBLE,
    plan_leader_track_id   BIGINT,
    plan_t_rel_s           FLOAT[],
    plan_x_m               FLOAT[],
    plan_y_m               FLOAT[],
    plan_heading_rad       FLOAT[],
    plan_speed_mps         FLOAT[],
    plan_accel_mps2        FLOAT[],
    -- control
    ctrl_throttle          DOUBLE,
    ctrl_brake             DOUBLE,
    ctrl_steering_rad      DOUBLE,
    ctrl_accel_cmd_mps2    DOUBLE,
    -- message ages: frame time minus the header stamp of the message held for the frame, s;
    -- NULL for evoeye's own runs, whose modules publish every message at the frame time
    age_localization_s     DOUBLE,
    age_obstacles_s        DOUBLE,
    age_predictions_s      DOUBLE,
    age_plan_s             DOUBLE,
    age_control_s          DOUBLE,
    -- ground truth of the ego (actor 0): evaluation only
    gt_x_m                 DOUBLE   NOT NULL,
    gt_y_m                 DOUBLE   NOT NULL,
    gt_heading_rad         DOUBLE   NOT NULL,
    gt_speed_mps           DOUBLE   NOT NULL,
    gt_vx_mps              DOUBLE   NOT NULL,
    gt_vy_mps              DOUBLE   NOT NULL,
    gt_accel_mps2          DOUBLE   NOT NULL,
    gt_ego_collision       BOOLEAN  NOT NULL,  -- nu(o_t) of Definition 1
    gt_collision_actor     BIGINT   NOT NULL,  -- -1 if none (64-bit, as the track ids)
    ingest_id              VARCHAR  NOT NULL,  -- the Parquet part these rows were written in
    logical_scenario       VARCHAR  NOT NULL,  -- partition key
    batch                  VARCHAR  NOT NULL   -- partition key
);
