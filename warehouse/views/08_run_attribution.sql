-- run_attribution: why each explained collision run collided, derived from `attribution`
-- (counterfactual re-simulations by `evoeye explain`) and never stored. One unit of credit per
-- run, split equally among the module oracles whose counterfactual avoids the collision (no ego
-- collision at all); 'compound' takes the whole unit when none does. A run counts once all four
-- oracle variants are stored for it (per software version). careful_driver_avoids is the
-- careful reference driver's verdict (NULL until it is stored).
CREATE OR REPLACE VIEW run_attribution AS
WITH variants AS (
    SELECT *
    FROM attribution
    QUALIFY row_number() OVER (
        PARTITION BY scenario_id, variant, software_version ORDER BY written_at, part_id
    ) = 1
),
oracles AS (
    SELECT *, replace(variant, 'oracle_', '') AS module
    FROM variants
    WHERE variant IN ('oracle_perception', 'oracle_prediction', 'oracle_planning',
                      'oracle_control')
),
runs AS (
    SELECT
        o.logical_scenario,
        o.scenario_id,
        o.software_version,
        count(*) FILTER (WHERE NOT o.collided) AS n_avoiding,
        any_value(NOT c.collided) AS careful_driver_avoids
    FROM oracles AS o
    LEFT JOIN variants AS c
        ON c.scenario_id = o.scenario_id AND c.software_version = o.software_version
        AND c.variant = 'careful_driver'
    GROUP BY o.logical_scenario, o.scenario_id, o.software_version
    HAVING count(*) = 4
)
SELECT
    r.logical_scenario,
    r.scenario_id,
    r.software_version,
    coalesce(o.module, 'compound') AS cause,
    1.0 / greatest(r.n_avoiding, 1) AS share,
    r.careful_driver_avoids
FROM runs AS r
LEFT JOIN oracles AS o
    ON o.scenario_id = r.scenario_id AND o.software_version = r.software_version
    AND NOT o.collided;

-- attribution_shares: per logical scenario and software version, each cause's share of the
-- explained collision runs (shares sum to 1), and the careful reference driver's record.
CREATE OR REPLACE VIEW attribution_shares AS
WITH per_run AS (
    SELECT logical_scenario, software_version, scenario_id,
           any_value(careful_driver_avoids) AS careful_driver_avoids
    FROM run_attribution
    GROUP BY logical_scenario, software_version, scenario_id
),
totals AS (
    SELECT logical_scenario, software_version, count(*) AS runs,
           count(*) FILTER (WHERE careful_driver_avoids) AS careful_avoided,
           count(careful_driver_avoids) AS careful_runs
    FROM per_run
    GROUP BY logical_scenario, software_version
)
SELECT
    a.logical_scenario,
    a.software_version,
    a.cause,
    sum(a.share) AS credit,
    t.runs,
    sum(a.share) / t.runs AS share,
    t.careful_avoided,
    t.careful_runs
FROM run_attribution AS a
JOIN totals AS t USING (logical_scenario, software_version)
GROUP BY a.logical_scenario, a.software_version, a.cause, t.runs, t.careful_avoided,
         t.careful_runs
ORDER BY a.logical_scenario, a.software_version,
         array_position(['perception', 'prediction', 'planning', 'control', 'compound'], a.cause);
