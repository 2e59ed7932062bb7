-- D_init of an evolution campaign: the train split of a logical scenario's round-0 runs.
SELECT s.scenario_id, s.params, s.collided, s.min_distance_m, s.duration_s, s.ads_profile
FROM scenarios AS s
JOIN scenario_splits($seed, $train_frac, $val_frac, test_batch := $test_batch) AS p
    USING (scenario_id)
WHERE s.logical_scenario = $scenario AND s.round = 0 AND p.split = 'train' AND s.status = 'ok'
ORDER BY s.scenario_id
