-- Rows of feedback (all, or one monitor version and / or feedback mode), from the parts ($glob).
-- Parts written before the feedback_mode column existed keyed prior-corrected feedback
-- `<version>+prior` in monitor_version: they read as (version, 'prior-corrected'), the others
-- as 'raw'. The empty branch gives the column a type where no part has it yet.
WITH parts AS (
    SELECT * FROM read_parquet($glob, union_by_name = true)
    UNION ALL BY NAME
    SELECT NULL::VARCHAR AS feedback_mode WHERE false
),
normalised AS (
    SELECT
        logical_scenario,
        scenario_id,
        regexp_replace(monitor_version, '\+prior$', '') AS monitor_version,
        coalesce(feedback_mode, CASE WHEN monitor_version LIKE '%+prior'
                                     THEN 'prior-corrected' ELSE 'raw' END) AS feedback_mode,
        feedback,
        n_contexts,
        part_id,
        written_at
    FROM parts
)
SELECT *
FROM normalised
WHERE ($version IS NULL OR monitor_version = $version)
  AND ($mode IS NULL OR feedback_mode = $mode)
ORDER BY monitor_version, feedback_mode, scenario_id
