-- What a campaign's records hold of some runs (scenario ids $ids): x, the outcome, the status.
SELECT scenario_id, params, collided, min_distance_m, duration_s, status
FROM scenarios
WHERE list_contains($ids, scenario_id);
