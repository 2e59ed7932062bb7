-- The collision runs to explain (`evoeye explain`): their RunSpec fields, optionally of one
-- logical scenario and one batch, without those whose every variant is stored already for
-- $software_version ($variants: how many variants a finished explanation has).
SELECT s.scenario_id, s.logical_scenario, s.batch, s.params, s.seed, s.source, s.round,
       s.ads_profile
FROM scenarios AS s
WHERE s.status = 'ok' AND s.collided
  AND ($logical_scenario IS NULL OR s.logical_scenario = $logical_scenario)
  AND ($batch IS NULL OR s.batch = $batch)
  AND (
      SELECT count(DISTINCT a.variant)
      FROM attribution AS a
      WHERE a.scenario_id = s.scenario_id AND a.software_version = $software_version
  ) < $variants
ORDER BY s.logical_scenario, s.batch, s.scenario_id;
