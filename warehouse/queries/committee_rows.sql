-- Rows of committee (all, or one campaign), in campaign and round order, from the parts.
SELECT *
FROM committee_parts($glob)
WHERE $campaign_id IS NULL OR campaign_id = $campaign_id
ORDER BY campaign_id, round
