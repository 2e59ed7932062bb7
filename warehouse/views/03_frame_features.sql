-- frame_features: the monitor inputs of the frames of committed runs (same visibility rule as
-- frames: a part is visible once its scenarios row is committed with the same ingest_id).
CREATE OR REPLACE VIEW frame_features AS
SELECT x.*
FROM frame_features_parquet AS x
SEMI JOIN scenarios AS s
    ON x.scenario_id = s.scenario_id AND x.ingest_id = s.ingest_id;

-- float32_of_bits(u): the IEEE 754 single whose bit pattern is the UINTEGER u, exactly.
CREATE OR REPLACE MACRO float32_of_bits(u) AS CAST(
    CASE
        WHEN (u >> 23) & 255 = 255 AND (u & 8388607) <> 0 THEN 'nan'::DOUBLE
        WHEN (u >> 23) & 255 = 255 THEN (1 - 2 * (u >> 31)::INTEGER) * 'inf'::DOUBLE
        WHEN (u >> 23) & 255 = 0 THEN (1 - 2 * (u >> 31)::INTEGER) * (u & 8388607)::DOUBLE
            * pow(2.0, -149)
        ELSE (1 - 2 * (u >> 31)::INTEGER) * (8388608 + (u & 8388607))::DOUBLE
            * pow(2.0, ((u >> 23) & 255)::INTEGER - 150)
    END AS FLOAT);

-- float32s(b): an array of frame_features (a BLOB of little-endian float32 values) as FLOAT[],
-- in stored (row-major) order, e.g. float32s(control)[5] is the ego speed, float32s(perception)
-- [9 * i + 1] the forward distance of the i-th nearest obstacle (i from 0).
CREATE OR REPLACE MACRO float32s(b) AS list_transform(
    range(octet_length(b) // 4),
    lambda i: float32_of_bits(('0x'  -- the 4 bytes of value i, most significant first
        || hex(b)[8 * i + 7 : 8 * i + 8] || hex(b)[8 * i + 5 : 8 * i + 6]
        || hex(b)[8 * i + 3 : 8 * i + 4] || hex(b)[8 * i + 1 : 8 * i + 2])::UINTEGER));
