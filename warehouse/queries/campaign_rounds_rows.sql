-- Rows of campaign_rounds (all, or one campaign), in campaign and round order, from the parts.
SELECT *
FROM campaign_rounds_parts($glob)
WHERE $campaign_id IS NULL OR campaign_id = $campaign_id
ORDER BY campaign_id, round
