-- Rows of attribution (all, or one software version), ordered by run and variant, from the parts.
SELECT *
FROM attribution_parts($glob)
WHERE $version IS NULL OR software_version = $version
ORDER BY software_version, scenario_id, variant
