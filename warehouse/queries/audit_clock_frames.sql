-- The pre-collision frames of the runs $scenario_ids with their Definition 1 label at horizon
-- $horizon_s (`evoeye audit`'s clock check): a frame is eligible iff its run never collides or
-- t_s < tau_col.
SELECT l.scenario_id, l.t_s, l.label
FROM frame_labels_h($horizon_s) AS l
WHERE list_contains($scenario_ids, l.scenario_id)
  AND (l.collision_time_s IS NULL OR l.t_s < l.collision_time_s)
ORDER BY l.scenario_id, l.frame;
