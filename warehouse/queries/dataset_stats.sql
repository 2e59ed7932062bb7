-- The paper's dataset table for horizon $horizon_s and split ($seed, $train_frac, $val_frac).
SELECT *
FROM dataset_stats_h($horizon_s, $seed, $train_frac, $val_frac)
ORDER BY logical_scenario, array_position(['train', 'val', 'test'], split);
