-- runtime_frames: frames without any gt_ (ground-truth) column: all a runtime monitor may see.
CREATE OR REPLACE VIEW runtime_frames AS
SELECT COLUMNS(lambda c: NOT starts_with(c, 'gt_'))
FROM frames;
