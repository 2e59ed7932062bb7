-- The runs monitor_scores holds for one monitor version, from the table's parts ($glob).
SELECT DISTINCT scenario_id
FROM monitor_scores_parts($glob)
WHERE monitor_version = $version
