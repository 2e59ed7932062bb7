-- Rows of feedback (all, or one monitor version and / or feedback mode), from the parts ($glob),
-- old parts read as the macro feedback_parts reads them (warehouse/parts.sql).
SELECT *
FROM feedback_parts($glob)
WHERE ($version IS NULL OR monitor_version = $version)
  AND ($mode IS NULL OR feedback_mode = $mode)
ORDER BY monitor_version, feedback_mode, scenario_id
