-- The scenario ids of a subset of runs; every filter is optional (NULL = no filter).
-- Splits come from scenario_splits($seed, $train_frac, $val_frac, test_batch := $test_batch)
-- ($test_batch: a held-out test batch or NULL), so a subset such as "the S1 validation runs"
-- or "violation runs of rounds >= 2" is one call.
SELECT s.scenario_id
FROM scenarios AS s
JOIN scenario_splits($seed, $train_frac, $val_frac, test_batch := $test_batch) AS p
    USING (scenario_id)
WHERE ($logical_scenario IS NULL OR s.logical_scenario = $logical_scenario)
  AND ($split IS NULL OR p.split = $split)
  AND ($source IS NULL OR s.source = $source)
  AND ($min_round IS NULL OR s.round >= $min_round)
  AND ($max_round IS NULL OR s.round <= $max_round)
  AND ($collided IS NULL OR s.collided = $collided)
  AND ($status IS NULL OR s.status = $status)
ORDER BY s.scenario_id;
