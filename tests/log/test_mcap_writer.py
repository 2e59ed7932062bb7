"""The lean McapWriter writes the same bytes as mcap's own Writer, and mcap reads them back."""

from __future__ import annotations

import io

import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from evoeye.log.mcap_writer import McapWriter, compressor

CHUNK_SIZE = 16 * 1024  # small, so the calls below span many chunks


def drive(writer: Writer | McapWriter, frames: bool = False) -> None:
    """The same sequence of calls for both writers, interleaving channels and record kinds;
    with `frames`, each frame's messages go in one `McapWriter.add_frame` call."""
    writer.start(profile="", library="test")
    a = writer.register_schema("a", "jsonschema", b'{"type": "object"}')
    b = writer.register_schema("b", "jsonschema", b"{}")
    channels = [writer.register_channel(f"/t{i}", "json", a if i % 2 else b) for i in range(4)]
    writer.add_metadata("evoeye.run", {"k": "v", "n": "1"})
    writer.add_attachment(
        create_time=0, log_time=5, name="m", media_type="application/json", data=b"{}"
    )
    for frame in range(600):
        # channels skip frames, so chunks index different channel sets
        sent = [(channel, b'{"v":%d}' % frame * (1 + i * 7 + frame % 11))
                for i, channel in enumerate(channels) if (frame + i) % 3]
        t_ns = frame * 50_000_000
        if frames:
            writer.add_frame([c for c, _ in sent], t_ns, [d for _, d in sent], frame)
        else:
            for channel, data in sent:
                writer.add_message(channel, t_ns, data, t_ns, frame)
    writer.add_metadata("second", {})
    writer.finish()


@pytest.mark.parametrize(
    ("theirs", "ours"),
    [(CompressionType.NONE, ""), (CompressionType.LZ4, "lz4"), (CompressionType.ZSTD, "zstd")],
)
def test_same_bytes_as_mcap_writer(theirs: CompressionType, ours: str) -> None:
    expected, got = io.BytesIO(), io.BytesIO()
    drive(Writer(expected, chunk_size=CHUNK_SIZE, compression=theirs))
    drive(McapWriter(got, compression=ours, level=3, chunk_size=CHUNK_SIZE))
    assert got.getvalue() == expected.getvalue()


@pytest.mark.parametrize("chunk_size", [CHUNK_SIZE, 700, 1])  # chunks close inside frames
def test_add_frame_writes_what_add_message_writes(chunk_size: int) -> None:
    expected, got = io.BytesIO(), io.BytesIO()
    drive(Writer(expected, chunk_size=chunk_size, compression=CompressionType.LZ4))
    drive(McapWriter(got, compression="lz4", chunk_size=chunk_size), frames=True)
    assert got.getvalue() == expected.getvalue()


def test_mcap_reads_a_zstd_level_1_file() -> None:
    buf = io.BytesIO()
    drive(McapWriter(buf, compression="zstd", level=1, chunk_size=CHUNK_SIZE))
    buf.seek(0)
    reader = make_reader(buf, validate_crcs=True)
    summary = reader.get_summary()
    assert summary is not None and len(summary.chunk_indexes) > 1
    n = sum(1 for _ in reader.iter_messages())
    assert n == summary.statistics.message_count == 1600
    assert [m.name for m in reader.iter_metadata()] == ["evoeye.run", "second"]


def test_unknown_compression_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown MCAP chunk compression"):
        compressor("gzip")
