-- Rows of monitor_scores (all, or one monitor version), from the table's parts ($glob).
SELECT *
FROM monitor_scores_parts($glob)
WHERE $version IS NULL OR monitor_version = $version
ORDER BY monitor_version, scenario_id, frame
