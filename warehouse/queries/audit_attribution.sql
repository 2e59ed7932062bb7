-- The attribution of the runs $scenario_ids (`evoeye audit`): the rows of view run_attribution
-- (one per cause with its share of the run's unit of credit, and the careful driver's verdict),
-- for each run's most recently explained software version.
WITH versions AS (
    SELECT scenario_id, arg_max(software_version, written_at) AS software_version
    FROM attribution
    WHERE list_contains($scenario_ids, scenario_id)
    GROUP BY scenario_id
)
SELECT r.logical_scenario, r.scenario_id, r.software_version, r.cause, r.share,
       r.careful_driver_avoids
FROM run_attribution AS r
JOIN versions AS v USING (scenario_id, software_version)
ORDER BY r.scenario_id, r.cause;
