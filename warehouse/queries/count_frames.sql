-- How many eligible frames (view eligible_frames) the runs listed in `selected_runs` have: the
-- rows windows.sql returns, which sizes its arrays.
SELECT count(*)::BIGINT AS n_frames
FROM eligible_frames AS e
SEMI JOIN selected_runs AS sel ON e.scenario_id = sel.scenario_id;
