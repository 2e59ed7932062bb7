-- eligible_frames: the frames that may enter anything learned or measured — every frame of a
-- run without a collision, and the frames strictly before the first collision of a run with
-- one. A log keeps its post-collision tail for viewing (table frames), but a frame at or after
-- the collision is no sample of "collision ahead or not": in the paper's setup the run ends
-- there. Every labelled frame, window, calibration set, feedback and metric is drawn from here.
-- tau_col (collision_time_s) is the time of the first frame whose ground truth has the ego in a
-- collision (gt_ego_collision); NULL for runs without one. Frame times are floats on a 20 Hz
-- grid, so the bound allows 1 microsecond of rounding.
-- A run of label_source 'none' (a recording imported without ground truth) has no label: none
-- of its frames is eligible, so it never enters a window, a calibration set or a metric.
CREATE OR REPLACE VIEW eligible_frames AS
SELECT scenario_id, frame, t_s, collision_time_s
FROM (
    SELECT
        scenario_id,
        frame,
        t_s,
        min(t_s) FILTER (WHERE gt_ego_collision) OVER (PARTITION BY scenario_id)
            AS collision_time_s
    FROM frames
    ANTI JOIN (SELECT scenario_id FROM scenarios WHERE label_source = 'none') USING (scenario_id)
)
WHERE collision_time_s IS NULL OR collision_time_s - t_s > 1e-6;

-- Frame labels, paper Definition 1:  y_t = 1  iff  0 < tau_col - tau_t <= H, on the eligible
-- frames (so tau_col - tau_t > 0 always holds; runs without a collision are all 0). A frame
-- exactly H before the collision is labelled 1, as the definition says (1 microsecond slack).
CREATE OR REPLACE MACRO frame_labels_h(h) AS TABLE
SELECT
    scenario_id,
    frame,
    t_s,
    collision_time_s,
    coalesce(collision_time_s - t_s <= h + 1e-6, false)::INTEGER AS label
FROM eligible_frames;

-- frame_labels: the labels at the paper's horizon H = 3 s.
CREATE OR REPLACE VIEW frame_labels AS
SELECT * FROM frame_labels_h(3.0);
