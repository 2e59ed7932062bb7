-- attribution: counterfactual re-simulations of collision runs (`evoeye explain`).
-- One row per (run, variant): the same scenario and seed re-simulated with one part of the
-- driving replaced, and whether the ego still collided. Variants:
--   'careful_driver'      the careful reference driver (sees everything, reacts 0.75 s after the
--                         partner's and the ego's constant-velocity futures first overlap within
--                         3 s, then brakes along its own path ramping to 7.59 m/s² in 0.6 s)
--   'oracle_perception'   perception = ground truth
--   'oracle_prediction'   prediction = the actors' true futures
--   'oracle_planning'     planning = a careful reference planner
--   'oracle_control'      control = an ideal actuator (no lag)
-- "Avoided" means no ego collision at all in the counterfactual: being struck from behind counts
-- as not avoided (conservative); struck_from_behind tells those collisions apart.
-- The cause of a run is derived from these rows in SQL (warehouse/views), never stored.
-- Append-only Parquet parts under warehouse/attribution/; a (scenario_id, variant,
-- software_version) triple is written at most once.
CREATE TABLE attribution (
    logical_scenario  VARCHAR  NOT NULL,
    scenario_id       VARCHAR  NOT NULL,
    software_version  VARCHAR  NOT NULL,  -- evoeye version that re-simulated the run
    variant           VARCHAR  NOT NULL,  -- see above
    collided          BOOLEAN  NOT NULL,  -- the ego still collided in the counterfactual
    collision_time_s  DOUBLE,             -- its first collision frame time, if any
    min_distance_m    DOUBLE,             -- min ego–actor footprint distance in the counterfactual
    struck_from_behind BOOLEAN,           -- its first collision: another actor into the ego's rear
    part_id           VARCHAR  NOT NULL,
    written_at        TIMESTAMP WITH TIME ZONE NOT NULL
);
