-- The runs the predictability check reads: one logical scenario's finished, labelled runs (an
-- imported recording without ground truth, label_source 'none', has no outcome to predict), of
-- one batch and / or one ADS profile (NULL: any), with their vector, outcome and ingestion time.
SELECT scenario_id, params, seed, collided, min_distance_m, ads_profile, batch, ingested_at
FROM scenarios
WHERE logical_scenario = $scenario AND status = 'ok' AND label_source <> 'none'
  AND ($batch IS NULL OR batch = $batch)
  AND ($ads IS NULL OR ads_profile = $ads)
ORDER BY scenario_id
