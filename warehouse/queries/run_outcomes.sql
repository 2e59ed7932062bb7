-- Whether and when each run of a logical scenario collided.
SELECT scenario_id, collided, collision_time_s
FROM scenarios
WHERE logical_scenario = $logical_scenario
