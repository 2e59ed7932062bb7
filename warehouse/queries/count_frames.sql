-- How many frames the runs listed in `selected_runs` have (sizes the arrays of windows.sql).
SELECT coalesce(sum(s.n_frames), 0)::BIGINT AS n_frames
FROM scenarios AS s
SEMI JOIN selected_runs AS sel ON s.scenario_id = sel.scenario_id;
