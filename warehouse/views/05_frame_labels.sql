-- Frame labels, paper Definition 1:  y_t = 1  iff  0 < tau_col - tau_t <= H.
-- tau_col is the time of the first frame whose ground truth has the ego in a collision
-- (gt_ego_collision); runs without one have tau_col = +inf and every label 0. The collision frame
-- itself (tau_col - tau_t = 0) and every later frame are 0.
-- Frame times are floats on a 20 Hz grid, so both bounds allow 1 microsecond of rounding
-- (a frame exactly H before the collision is labelled 1, as the definition says).
CREATE OR REPLACE MACRO frame_labels_h(h) AS TABLE
SELECT
    scenario_id,
    frame,
    t_s,
    collision_time_s,
    coalesce(
        collision_time_s - t_s > 1e-6 AND collision_time_s - t_s <= h + 1e-6, false
    )::INTEGER AS label
FROM (
    SELECT
        scenario_id,
        frame,
        t_s,
        min(t_s) FILTER (WHERE gt_ego_collision) OVER (PARTITION BY scenario_id)
            AS collision_time_s
    FROM frames
);

-- frame_labels: the labels at the paper's horizon H = 3 s.
CREATE OR REPLACE VIEW frame_labels AS
SELECT * FROM frame_labels_h(3.0);
