-- Labels y_t for horizon H (Definition 1) of every eligible frame (view eligible_frames: none at
-- or after a run's collision) of the runs listed in `selected_runs` (a relation with a
-- scenario_id column that the caller registers), in (scenario_id, frame) order: the order of the
-- windows, one per row. Parameter: $horizon_s = H.
--
-- `evoeye/store/windows.py` builds the runtime contexts c_t of length L (Definition 2) on this
-- order: the context of the row at position p of its run holds the rows of positions
-- p-L+1 … p, clamped to the run's first row and masked where clamped (the first frames of a run
-- repeat its first frame on the left). A frame's context frames are earlier than it, so they
-- are eligible too.
--
-- The monitor inputs (table frame_features: runtime signals only, no ground truth) are not
-- carried here: `feature_rows` (a relation the caller registers: scenario_id, frame, ingest_id,
-- feature_row) numbers the frame_features rows the caller read from the runs' parts (query
-- window_parts), and `feature_row` names the one holding the frame's inputs (NULL if the caller
-- holds none). As in view frame_features, a row counts only from the part its run is committed
-- with (same ingest_id). The ego's localization estimate (map frame) comes from runtime_frames.
SELECT
    k.feature_row,
    n.scenario_id,
    n.frame,
    n.t_s,
    n.label,
    r.loc_x_m,
    r.loc_y_m
FROM frame_labels_h($horizon_s) AS n
SEMI JOIN selected_runs AS sel
    ON n.scenario_id = sel.scenario_id
JOIN scenarios AS s
    ON s.scenario_id = n.scenario_id
LEFT JOIN feature_rows AS k
    ON k.scenario_id = n.scenario_id AND k.frame = n.frame AND k.ingest_id = s.ingest_id
JOIN runtime_frames AS r
    ON r.scenario_id = n.scenario_id AND r.frame = n.frame
ORDER BY n.scenario_id, n.frame;
