-- Robust Hard Set (issue 11): the unsafe test frames that a strict majority of k re-seeded
-- initial monitors (G_0's recipe trained with k seeds) miss, each at its own threshold
-- (score <= threshold, calibrated for FPR 0.05), plus every safe test frame. The paper's Hard
-- Set is one G_0's misses, so it measures that model's seed noise, and its negatives are the
-- early frames of its collision runs, which favours monitors that alarm often; here a frame is
-- hard only if the recipe misses it whatever the seed, and false alarms are paid on the whole
-- Test Set's safe frames. Only frames that every one of the k monitors scored count.
-- The caller registers `monitor_scores` (the table of that name, e.g. read_scores(...)).
-- Parameters: $monitor_versions (VARCHAR[], the k monitors) and $thresholds (DOUBLE[], one per
-- monitor, same order), $logical_scenario, $horizon_s, and the split ($seed, $train_frac,
-- $val_frac, $test_batch). One row per frame: scenario_id, frame, t_s, label, and missed_by
-- (how many of the k monitors miss it; 0 … k, counted for safe frames too).
WITH g0 AS (
    SELECT unnest($monitor_versions) AS monitor_version, unnest($thresholds) AS threshold
),
scored AS (
    SELECT
        s.scenario_id,
        s.frame,
        l.t_s,
        l.label,
        count(*) AS scored_by,
        count(*) FILTER (WHERE s.score <= g0.threshold) AS missed_by
    FROM monitor_scores AS s
    JOIN g0 USING (monitor_version)
    JOIN frame_labels_h($horizon_s) AS l USING (scenario_id, frame)
    JOIN scenario_splits($seed, $train_frac, $val_frac, test_batch := $test_batch) AS p
        USING (scenario_id)
    WHERE p.logical_scenario = $logical_scenario AND p.split = 'test'
    GROUP BY s.scenario_id, s.frame, l.t_s, l.label
)
SELECT scenario_id, frame, t_s, label, missed_by
FROM scored
WHERE scored_by = len($monitor_versions) AND (label = 0 OR 2 * missed_by > scored_by)
ORDER BY scenario_id, frame;
