-- The runs listed in `selected_runs` (a relation with a scenario_id column that the caller
-- registers) that are committed, in scenario_id order — the order of their windows — with the
-- part that commits each: its frames and frame_features rows sit in the part <ingest_id>.parquet
-- of its partition (evoeye/store/parts.py), the same rows in the same order in both tables.
-- `evoeye/store/windows.py` reads those parts, keeps the eligible frames (view eligible_frames)
-- and labels them (frame_labels_h) with `evoeye/store/labels.py`, the views' numpy twin.
-- An unlabelled run (label_source 'none') has no eligible frame, so no window, whoever asks.
SELECT s.scenario_id, s.logical_scenario, s.batch, s.ingest_id
FROM scenarios AS s
SEMI JOIN selected_runs AS sel ON s.scenario_id = sel.scenario_id
WHERE s.label_source <> 'none'
ORDER BY s.scenario_id;
