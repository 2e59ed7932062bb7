-- Runtime contexts c_t of length L (Definition 2) and labels y_t for horizon H (Definition 1),
-- one row per eligible frame (view eligible_frames: none at or after a run's collision) of the
-- runs listed in `selected_runs` (a relation with a scenario_id column that the caller
-- registers). Parameters: $context_len = L >= 1, $horizon_s = H.
--
-- `row` numbers the frames in (scenario_id, frame) order from 0; rows may arrive in any order.
-- ctx_row[k], k = 0 .. L-1 oldest first, is the `row` of frame t-L+1+k clamped to the run's
-- first frame: c_t = (m_max(1,t-L+1), ..., m_t) read element-wise, so the first frames of a run
-- repeat its first frame on the left, and ctx_mask[k] is false exactly on those repeated slots.
-- A frame's context frames are earlier than it, so they are eligible too.
-- The monitor inputs come from frame_features (runtime signals only; no ground truth), the
-- ego's localization estimate (map frame) from runtime_frames.
WITH labelled AS (
    SELECT l.scenario_id, l.frame, l.t_s, l.label
    FROM frame_labels_h($horizon_s) AS l
    SEMI JOIN selected_runs AS sel ON l.scenario_id = sel.scenario_id
),
numbered AS (
    SELECT
        *,
        row_number() OVER (ORDER BY scenario_id, frame) - 1 AS row,
        row_number() OVER (PARTITION BY scenario_id ORDER BY frame) - 1 AS pos
    FROM labelled
)
SELECT
    n.row,
    n.scenario_id,
    n.frame,
    n.t_s,
    n.label,
    list_transform(
        range($context_len),
        lambda k: n.row - n.pos + greatest(n.pos - $context_len + 1 + k, 0)
    ) AS ctx_row,
    list_transform(range($context_len), lambda k: n.pos - $context_len + 1 + k >= 0) AS ctx_mask,
    r.loc_x_m,
    r.loc_y_m,
    x.* EXCLUDE (scenario_id, frame, ingest_id, logical_scenario, batch)
FROM numbered AS n
JOIN frame_features AS x
    ON x.scenario_id = n.scenario_id AND x.frame = n.frame
JOIN runtime_frames AS r
    ON r.scenario_id = n.scenario_id AND r.frame = n.frame;
