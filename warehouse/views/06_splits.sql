-- Train / val / test splits, by scenario and never by frame.
-- u = (first 8 hex digits of md5('<seed>:<scenario_id>')) / 2^32 is uniform in [0, 1) and
-- depends only on the scenario id and the seed: a run keeps its split when data is added, and
-- the same seed always gives the same split (md5 is stable, unlike DuckDB's hash()).
-- Round-0 runs (the initial data) go to train if u < train_frac, to val if
-- u < train_frac + val_frac, else to test. Runs acquired during evolution (round >= 1) are
-- training data, D_{r+1} = D_r ∪ D'_r (Definition 3): they never enter the held-out sets.
-- test_batch (optional) names a round-0 batch simulated apart as a fixed Test Set: its runs are
-- always 'test'; the other round-0 runs split by u as above.
-- Unlabelled runs (label_source 'none') are in no split: they train, calibrate and test nothing.
CREATE OR REPLACE MACRO scenario_splits(seed, train_frac, val_frac, test_batch := NULL) AS TABLE
SELECT
    scenario_id,
    logical_scenario,
    CASE
        WHEN round >= 1 THEN 'train'
        WHEN batch = test_batch THEN 'test'
        WHEN u < train_frac THEN 'train'
        WHEN u < train_frac + val_frac THEN 'val'
        ELSE 'test'
    END AS split,
    u
FROM (
    SELECT
        scenario_id,
        logical_scenario,
        round,
        batch,
        ('0x' || md5(CAST(seed AS VARCHAR) || ':' || scenario_id)[1:8])::UBIGINT
            / 4294967296.0 AS u
    FROM scenarios
    WHERE label_source <> 'none'
);

-- splits: seed 0 and the paper's proportions (6 h train; the other 6 h split val:test = 1:3).
CREATE OR REPLACE VIEW splits AS
SELECT * FROM scenario_splits(0, 0.5, 0.125);
