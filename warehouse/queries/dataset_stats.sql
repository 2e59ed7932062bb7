-- The paper's dataset table for horizon $horizon_s and split ($seed, $train_frac, $val_frac,
-- $test_batch: a held-out test batch or NULL).
SELECT *
FROM dataset_stats_h($horizon_s, $seed, $train_frac, $val_frac, test_batch := $test_batch)
ORDER BY logical_scenario, array_position(['train', 'val', 'test'], split);
