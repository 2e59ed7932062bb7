-- committee: the companions of an evolution campaign's monitor after each round, for the
-- `disagreement` strategy. Its committee after round r is G_r (campaign_rounds.monitor_version)
-- and these K − 1 monitors, trained beside G_r from other seeds on the same runs; a run's
-- disagreement is the spread of the committee's scores on it (feedback rows of mode
-- 'disagreement-k<K>…' under G_r). (campaign_id, round) is written at most once.
CREATE TABLE committee (
    campaign_id  VARCHAR   NOT NULL,  -- the campaign (campaign_rounds.campaign_id)
    round        INTEGER   NOT NULL,  -- r; 0 = the start (companions of G_0)
    companions   VARCHAR[] NOT NULL,  -- monitor versions of members 1 .. K − 1
    written_at   TIMESTAMP WITH TIME ZONE NOT NULL
);
