"""A cyber record → an evoeye run, through the frame assembler Autoware's bags go through.

Channels play the roles of Autoware's topics (`APOLLO_TOPICS`); the converters are Apollo's
(`convert.py`), the frames, ages, labels and notes the same (docs/autoware.md, "Frames, rates
and ages"). A record decodes with the descriptors each channel carries, else the vendored ones.
A record evoeye exported carries its run's identity on the channel `RUN_CHANNEL` (an
`apollo.common.Header` whose `module_name` is the run record's JSON) and comes back under it;
any other record is a run of logical scenario `external`, its id from its content (every
message's channel, type, time and bytes).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from evoeye.sources.apollo import convert
from evoeye.sources.apollo.protos import classes_from_proto_desc, vendored
from evoeye.sources.apollo.record import Record, RecordError, read_record
from evoeye.sources.autoware.bag import (
    EXTERNAL_SCENARIO,
    BagError,
    Content,
    ImportedRun,
    content_of,
    imported_run,
    run_identity,
)
from evoeye.sources.autoware.config import REQUIRED_ROLES, Mapping, Topics
from evoeye.sources.autoware.convert import ConversionError
from evoeye.sources.autoware.frames import Frame, FrameAssembler, SourceError
from evoeye.sources.autoware.importer import Recordings
from evoeye.sources.autoware.labels import label_source

SOFTWARE = "apollo"
RUN_CHANNEL = "/evoeye/run"
APOLLO_TOPICS = Topics(
    odometry="/apollo/localization/pose", acceleration="",
    objects="/apollo/perception/obstacles", predicted="/apollo/prediction",
    trajectory="/apollo/planning", control="/apollo/control", velocity_limit="", mrm_state="",
    ground_truth_objects="/simulation/ground_truth/obstacles",
    ground_truth_ego="/simulation/ground_truth/pose", collision="")


def apollo_mapping(vehicle: convert.ApolloVehicle | None = None) -> Mapping:
    """Apollo's channels, no planning-factor topics (the decision is in the trajectory)."""
    return Mapping(APOLLO_TOPICS, {}, vehicle or convert.ApolloVehicle())


def find_records(paths: Sequence[Path]) -> list[Path]:
    """The records named: `.record` files (with or without a split suffix, `x.record.00000`),
    or folders holding them (one level down)."""
    out: list[Path] = []
    for p in paths:
        if p.is_dir():
            out += sorted(q for q in p.iterdir() if q.is_file() and ".record" in q.name)
        else:
            out.append(p)
    return out


def _read(path: Path) -> Record:
    try:
        return read_record(path)
    except (RecordError, OSError) as e:
        raise BagError(f"{path}: (record): {e}") from None


def _content(record: Record) -> Content:
    kinds = {c.name: c.message_type for c in record.channels.values()}
    return content_of(record.channels, ((t_ns, name, kinds.get(name, ""), raw)
                                        for name, t_ns, raw in record.messages))


def _identity(path: Path, record: Record) -> dict[str, Any]:
    raws = [raw for name, _, raw in record.messages if name == RUN_CHANNEL]
    if not raws:
        return {}
    header = vendored()["apollo.common.Header"].FromString(raws[0])
    return run_identity(path, header.module_name, RUN_CHANNEL)


def record_run_id(path: Path) -> tuple[str, str]:
    """(logical scenario, scenario id) the record imports as."""
    record = _read(Path(path))
    identity = _identity(Path(path), record)
    sid = identity.get("scenario_id") or f"{SOFTWARE}_{_content(record).digest[:16]}"
    return identity.get("logical_scenario", EXTERNAL_SCENARIO), sid


def _check(path: Path, record: Record, content: Content, mapping: Mapping) -> dict[str, str]:
    """Channel → role of the channels to decode; BagError for a missing or empty required
    channel or an unknown type."""
    if not record.messages:
        raise BagError(f"{path}: (record): no message in the record (its "
                       f"{len(record.channels)} channels are empty)")
    roles = mapping.roles()
    for role in REQUIRED_ROLES:
        channel = getattr(mapping.topics, role)
        if channel not in record.channels:
            raise BagError(f"{path}: {channel}: missing required channel ({role})")
        if not content.counts.get(channel):
            raise BagError(f"{path}: {channel}: no message on a required channel ({role})")
    wanted = {c: roles[c] for c in record.channels if c in roles}
    for channel, role in wanted.items():
        try:
            convert.converter(role, record.channels[channel].message_type)
        except ConversionError as e:
            raise BagError(f"{path}: {channel}: {e}") from None
    return wanted


def read_record_run(path: str | Path, mapping: Mapping | None = None) -> ImportedRun:
    """Convert one record; BagError naming the record, the channel and the problem."""
    path = Path(path)
    mapping = mapping or apollo_mapping()
    record = _read(path)
    content = _content(record)
    wanted = _check(path, record, content, mapping)
    source = label_source(mapping, set(wanted))
    assembler = FrameAssembler(mapping, source, lookup=convert.converter,
                               stamp=convert.stamp_ns)
    classes: dict[str, type] = {}
    frames: list[Frame] = []
    try:
        for name, t_ns, raw in record.messages:
            if name not in wanted:
                continue
            channel = record.channels[name]
            if name not in classes:
                own = classes_from_proto_desc(channel.proto_desc) if channel.proto_desc else {}
                classes[name] = own.get(channel.message_type) or vendored()[channel.message_type]
            frames.extend(assembler.push(name, channel.message_type,
                                         classes[name].FromString(raw), t_ns))
        frames.extend(assembler.finish())
    except SourceError as e:
        raise BagError(f"{path}: {e}") from None
    except Exception as e:  # protobuf's DecodeError on damaged bytes, and kin
        raise BagError(f"{path}: (record): bad record ({type(e).__name__}: {e})") from None
    return imported_run(path, mapping, assembler, frames, _identity(path, record), content,
                        SOFTWARE)


RECORDS = Recordings(find=find_records, run_id=record_run_id, read=read_record_run)
