-- The logical scenarios that have runs in the warehouse.
SELECT DISTINCT logical_scenario FROM scenarios ORDER BY logical_scenario
