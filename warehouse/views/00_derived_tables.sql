-- The tables later stages append to (schemas/warehouse/<table>.sql), one view each over
-- <table>_parquet: every part of the table, created by evoeye over warehouse/<table>/*.parquet
-- (the empty declared table while there is none). Writers key their rows, so a key is never
-- written twice and the views need not deduplicate.

-- attribution: `evoeye explain`'s counterfactual outcomes, one row per (run, variant, version).
CREATE OR REPLACE VIEW attribution AS
SELECT * FROM attribution_parquet;

-- monitor_scores: one monitor version's risk per frame (`evoeye evaluate`, campaign assessments).
CREATE OR REPLACE VIEW monitor_scores AS
SELECT * FROM monitor_scores_parquet;

-- campaign_rounds: one row per finished round of an evolution campaign; `metrics` is JSON.
CREATE OR REPLACE VIEW campaign_rounds AS
SELECT * FROM campaign_rounds_parquet;

-- feedback: f_r(x) of a run under a monitor version. Parts written before the feedback_mode
-- column existed keyed prior-corrected feedback `<version>+prior` in monitor_version: they read
-- as (version, 'prior-corrected'), the others as 'raw' (as the query feedback_rows reads them).
CREATE OR REPLACE VIEW feedback AS
SELECT
    logical_scenario,
    scenario_id,
    regexp_replace(monitor_version, '\+prior$', '') AS monitor_version,
    coalesce(feedback_mode, CASE WHEN monitor_version LIKE '%+prior'
                                 THEN 'prior-corrected' ELSE 'raw' END) AS feedback_mode,
    feedback,
    n_contexts,
    part_id,
    written_at
FROM feedback_parquet;
