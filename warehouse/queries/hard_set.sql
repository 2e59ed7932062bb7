-- Hard Set (paper §V, RQ2): the unsafe test frames the initial monitor misses at its threshold
-- (score <= $threshold, the threshold calibrated for FPR 0.05), plus the safe frames of those
-- same runs. Only eligible frames have labels (frame_labels_h), as in every evaluation.
-- The caller registers `monitor_scores` (the table of that name, e.g. read_scores(...)).
-- Parameters: $monitor_version, $threshold, $logical_scenario, $horizon_s, and the split
-- ($seed, $train_frac, $val_frac, $test_batch). One row per frame: scenario_id, frame, t_s,
-- label, score.
WITH scored AS (
    SELECT s.scenario_id, s.frame, l.t_s, l.label, s.score
    FROM monitor_scores AS s
    JOIN frame_labels_h($horizon_s) AS l USING (scenario_id, frame)
    JOIN scenario_splits($seed, $train_frac, $val_frac, test_batch := $test_batch) AS p
        USING (scenario_id)
    WHERE s.monitor_version = $monitor_version
        AND p.logical_scenario = $logical_scenario
        AND p.split = 'test'
),
missed AS (
    SELECT DISTINCT scenario_id FROM scored WHERE label = 1 AND score <= $threshold
)
SELECT scenario_id, frame, t_s, label, score
FROM scored
WHERE (label = 1 AND score <= $threshold)
    OR (label = 0 AND scenario_id IN (SELECT scenario_id FROM missed))
ORDER BY scenario_id, frame;
