-- Table macros `<table>_parts(files)`: the rows of the tables later stages append to
-- (schemas/warehouse/<table>.sql) from some of their Parquet parts — a glob or a list of files.
-- The views of the same names read every part through them (evoeye.store.catalog); the code
-- reads one key's parts through them (warehouse/queries/*_rows.sql, evoeye.store.derived).
-- Writers key their rows, so a key is never written twice and nothing needs deduplicating.

-- attribution: `evoeye explain`'s counterfactual outcomes, one row per (run, variant, version).
CREATE OR REPLACE MACRO attribution_parts(files) AS TABLE
SELECT * FROM read_parquet(files, union_by_name = true);

-- monitor_scores: one monitor version's risk per frame (`evoeye evaluate`, campaign assessments).
CREATE OR REPLACE MACRO monitor_scores_parts(files) AS TABLE
SELECT * FROM read_parquet(files);

-- campaign_rounds: one row per finished round of an evolution campaign; `metrics` is JSON.
CREATE OR REPLACE MACRO campaign_rounds_parts(files) AS TABLE
SELECT * FROM read_parquet(files);

-- committee: the companion monitors a `disagreement` campaign trained beside G_r, per round.
CREATE OR REPLACE MACRO committee_parts(files) AS TABLE
SELECT * FROM read_parquet(files);

-- feedback: f_r(x) of a run under a monitor version. Parts written before the feedback_mode
-- column existed keyed prior-corrected feedback `<version>+prior` in monitor_version: they read
-- as (version, 'prior-corrected'), the others as 'raw'. The empty branch gives the column a type
-- where no part has it yet.
CREATE OR REPLACE MACRO feedback_parts(files) AS TABLE
WITH parts AS (
    SELECT * FROM read_parquet(files, union_by_name = true)
    UNION ALL BY NAME
    SELECT NULL::VARCHAR AS feedback_mode WHERE false
)
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
FROM parts;
