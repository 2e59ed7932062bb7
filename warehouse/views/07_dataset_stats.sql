-- The paper's dataset table (Table "Dataset statistics") per logical scenario and split:
-- scenarios, violations (%), frames, unsafe frames (%), for horizon h and a split (seed, shares,
-- optional held-out test batch); max_round (optional) leaves out the runs of later rounds, e.g.
-- 0: the initial data only, without the runs campaigns acquired (which always train).
-- Only runs with status 'ok' count; failed runs are counted apart.
CREATE OR REPLACE MACRO dataset_stats_h(h, seed, train_frac, val_frac, test_batch := NULL,
                                        max_round := NULL) AS TABLE
WITH per_run AS (
    SELECT
        s.scenario_id,
        s.logical_scenario,
        p.split,
        s.status,
        s.collided,
        coalesce(l.n_frames, 0) AS n_frames,
        coalesce(l.n_unsafe, 0) AS n_unsafe
    FROM scenarios AS s
    JOIN scenario_splits(seed, train_frac, val_frac, test_batch := test_batch) AS p
        USING (scenario_id)
    LEFT JOIN (
        SELECT scenario_id, count(*) AS n_frames, sum(label) AS n_unsafe
        FROM frame_labels_h(h)
        GROUP BY scenario_id
    ) AS l USING (scenario_id)
    WHERE max_round IS NULL OR s.round <= max_round
)
SELECT
    logical_scenario,
    split,
    count(*) FILTER (WHERE status = 'ok') AS scenarios,
    count(*) FILTER (WHERE status = 'ok' AND collided) AS violations,
    round(100.0 * violations / nullif(scenarios, 0), 1) AS violations_pct,
    coalesce(sum(n_frames) FILTER (WHERE status = 'ok'), 0)::BIGINT AS frames,
    coalesce(sum(n_unsafe) FILTER (WHERE status = 'ok'), 0)::BIGINT AS unsafe_frames,
    round(100.0 * unsafe_frames / nullif(frames, 0), 1) AS unsafe_pct,
    count(*) FILTER (WHERE status <> 'ok') AS failed
FROM per_run
GROUP BY logical_scenario, split;

-- dataset_stats: H = 3 s and the default splits.
CREATE OR REPLACE VIEW dataset_stats AS
SELECT * FROM dataset_stats_h(3.0, 0, 0.5, 0.125)
ORDER BY logical_scenario, array_position(['train', 'val', 'test'], split);
