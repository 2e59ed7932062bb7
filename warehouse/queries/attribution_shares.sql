-- The attribution shares (view attribution_shares) of one logical scenario, or of all (NULL).
SELECT *
FROM attribution_shares
WHERE $logical_scenario IS NULL OR logical_scenario = $logical_scenario;
