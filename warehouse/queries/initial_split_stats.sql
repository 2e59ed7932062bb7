-- The initial (round-0) runs of one logical scenario per split (dataset_stats_h without the runs
-- campaigns acquired, which always train): runs, violations, frames and unsafe frames.
-- Parameters: $logical_scenario, $horizon_s, and the split ($seed, $train_frac, $val_frac,
-- $test_batch).
SELECT split, scenarios, violations, frames, unsafe_frames, failed
FROM dataset_stats_h($horizon_s, $seed, $train_frac, $val_frac, test_batch := $test_batch,
                     max_round := 0)
WHERE logical_scenario = $logical_scenario
ORDER BY array_position(['train', 'val', 'test'], split);
