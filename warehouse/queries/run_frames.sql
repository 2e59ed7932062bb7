-- The runtime frames of one run, in time order (e.g. to replay it through a monitor).
SELECT *
FROM runtime_frames
WHERE scenario_id = $scenario_id
ORDER BY frame;
