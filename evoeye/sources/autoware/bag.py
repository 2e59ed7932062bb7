"""A rosbag2 bag (MCAP or `.db3`, a folder or one file) → an evoeye run: metadata and frames.

Only the mapped topics are decoded (point clouds and images never are). The bag's definitions
decode it when it embeds them (MCAP); otherwise ROS 2 Humble's types and the vendored Autoware
ones do (`typestore`). A bag that evoeye exported carries its run's identity (rosbag2
custom data `evoeye.run`: scenario id, logical scenario, parameters, seed, round, ADS profile):
it comes back under that id. Any other bag is a run of logical scenario `external`, its id
from its content (every message's topic, type, receive time and bytes, `content_digest`), not
from its storage: the same recording as MCAP and as `.db3`, or imported twice, is one run.
Labels come from the bag's ground truth alone (`labels.py`), never from that record.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import orjson

from evoeye.ads import DEFAULT_PROFILE
from evoeye.log.records import UNLABELLED
from evoeye.sources.autoware.config import REQUIRED_ROLES, Mapping
from evoeye.sources.autoware.convert import ConversionError, converter
from evoeye.sources.autoware.frames import Frame, FrameAssembler, SourceError
from evoeye.sources.autoware.labels import label_source
from evoeye.sources.autoware.typestore import typestore

EXTERNAL_SCENARIO = "external"
RUN_KEY = "evoeye.run"  # rosbag2 custom data of an exported bag: its run's identity (JSON)
IDENTITY = ("scenario_id", "logical_scenario", "param_names", "params", "seed", "source", "round")
# kept too, with its value when a bag lacks it: a bag exported before profiles was driven by the
# default profile; another stack's bag names none of evoeye's ADS profiles, and takes the run
# record's default too
OPTIONAL_IDENTITY = {"ads_profile": DEFAULT_PROFILE}
SOFTWARE = "autoware"


class BagError(ValueError):
    """A bag that cannot be imported: one line naming the bag, the topic and the problem."""


@dataclass
class ImportedRun:
    """One bag as an evoeye run: typed run metadata (schemas/mcap/run.v1.json) and its frames."""

    path: Path
    metadata: dict[str, Any]
    frames: list[Frame]
    notes: list[str] = field(default_factory=list)  # accepted oddities, one line each

    def messages(self) -> list[dict[str, dict[str, Any]]]:
        return [f.messages for f in self.frames]


@dataclass(frozen=True)
class Content:
    """What a bag holds, whatever its storage: a digest of its messages and their count per
    topic."""

    digest: str  # sha1 over (receive ns, topic, type, sha1 of the CDR bytes), sorted
    counts: dict[str, int]  # messages per topic


def content_of(topics: Iterable[str], messages: Iterable[tuple[int, str, str, bytes]]
               ) -> Content:
    """The content of a recording of `topics` with `messages` (receive ns, topic, type,
    serialized bytes), in any order."""
    rows, counts = [], dict.fromkeys(topics, 0)
    for log_ns, topic, msgtype, raw in messages:
        rows.append((log_ns, topic, msgtype, hashlib.sha1(raw).digest()))
        counts[topic] = counts.get(topic, 0) + 1
    h = hashlib.sha1()
    for log_ns, topic, msgtype, digest in sorted(rows):
        h.update(b"%d\0%s\0%s\0" % (log_ns, topic.encode(), msgtype.encode()) + digest)
    return Content(h.hexdigest(), counts)


def content_digest(reader: Any) -> Content:
    """The bag's content (module doc), read without decoding a message."""
    return content_of((c.topic for c in reader.connections),
                      ((log_ns, c.topic, c.msgtype, raw) for c, log_ns, raw in reader.messages()))


def _check_counts(path: Path, content: Content, mapping: Mapping) -> None:
    """BagError for a bag without a message, or a required topic without one."""
    if not any(content.counts.values()):
        raise BagError(f"{path}: (bag): no message in the bag (its {len(content.counts)} "
                       "topics are empty)")
    for role in REQUIRED_ROLES:
        topic = getattr(mapping.topics, role)
        if not content.counts.get(topic):
            raise BagError(f"{path}: {topic}: no message on a required topic ({role})")


def _custom_data(reader: Any) -> dict[str, str]:
    for sub in reader.readers:
        metadata = getattr(getattr(sub, "storage", None), "metadata", None)
        custom = getattr(metadata, "custom", None)
        if custom:
            return dict(custom)
    return {}


def _check_topics(reader: Any, mapping: Mapping, path: Path) -> list[Any]:
    """The connections to decode; BagError for a missing required topic or an unknown type."""
    roles = mapping.roles()
    present = {c.topic: c for c in reader.connections}
    if mapping.topics.odometry not in present:
        raise BagError(f"{path}: {mapping.topics.odometry}: no ego odometry in the bag "
                       "(nav_msgs/msg/Odometry; set [topics] odometry in a mapping file)")
    for role in REQUIRED_ROLES:
        topic = getattr(mapping.topics, role)
        if topic not in present:
            raise BagError(f"{path}: {topic}: missing required topic ({role})")
    wanted = [c for c in reader.connections if c.topic in roles]
    for c in wanted:
        try:
            converter(roles[c.topic], c.msgtype)
        except ConversionError as e:
            raise BagError(f"{path}: {c.topic}: {e}") from None
    return wanted


def _identity(path: Path, custom: dict[str, str]) -> dict[str, Any]:
    """The run identity an exported bag carries; {} for any other bag."""
    return run_identity(path, custom.get(RUN_KEY), f"custom data {RUN_KEY}")


def run_identity(path: Path, text: str | bytes | None, where: str) -> dict[str, Any]:
    """The run identity of an exported recording (the JSON it carries at `where`), {} if
    none."""
    if text is None:
        return {}
    try:
        record = orjson.loads(text)
        return {**{k: record[k] for k in IDENTITY},
                **{k: record.get(k, default) for k, default in OPTIONAL_IDENTITY.items()}}
    except (orjson.JSONDecodeError, KeyError, TypeError) as e:
        raise BagError(f"{path}: {where}: malformed ({e})") from None


def _scenario_id(identity: dict[str, Any], content: Content, software: str = SOFTWARE) -> str:
    return identity.get("scenario_id", f"{software}_{content.digest[:16]}")


def bag_run_id(path: str | Path) -> tuple[str, str]:
    """(logical scenario, scenario id) the bag imports as, without decoding a message."""
    from rosbags.highlevel import AnyReader

    path = Path(path)
    try:
        with AnyReader([path], default_typestore=typestore()) as reader:
            identity = _identity(path, _custom_data(reader))
            sid = identity["scenario_id"] if identity else _scenario_id({},
                                                                         content_digest(reader))
    except BagError:
        raise
    except Exception as e:  # as read_bag: a bag rosbags cannot open
        raise BagError(f"{path}: (bag): unreadable bag ({type(e).__name__}: {e})") from None
    return identity.get("logical_scenario", EXTERNAL_SCENARIO), sid


def run_metadata(identity: dict[str, Any], content: Content, assembler: FrameAssembler,
                 frames: list[Frame], source: str, software: str = SOFTWARE) -> dict[str, Any]:
    """The run record (schemas/mcap/run.v1.json) of a recording's frames: its identity if it
    carries one (an exported recording), else a run of logical scenario `external`."""
    truth = assembler.truth
    first = next((f for f in frames if f.messages["/sim/ground_truth"]["ego_collision"]), None)
    dt_s = 1.0 / assembler.mapping.rate_hz
    return {
        "scenario_id": _scenario_id(identity, content, software),
        "logical_scenario": identity.get("logical_scenario", EXTERNAL_SCENARIO),
        "param_names": identity.get("param_names", []),
        "params": identity.get("params", []),
        "seed": identity.get("seed", 0),
        "batch": "",  # the importer's batch
        "source": identity.get("source", software),
        "round": identity.get("round", 0),
        "ads_profile": identity.get("ads_profile", DEFAULT_PROFILE),
        "software_version": software,
        "rate_hz": assembler.mapping.rate_hz,
        "status": "ok",
        "reason": "",
        "collided": first is not None,
        "collision_time_s": None if first is None else first.messages["/sim/ground_truth"]["t_s"],
        "other_actor": None if first is None else truth.collision_actor,
        "duration_s": len(frames) * dt_s,
        "min_distance_m": truth.min_distance_m,
        "label_source": source,
    }


def read_bag(path: str | Path, mapping: Mapping | None = None) -> ImportedRun:
    """Convert one bag; BagError naming the bag, the topic and the problem if it cannot be."""
    from rosbags.highlevel import AnyReader, AnyReaderError

    path = Path(path)
    mapping = mapping or Mapping()
    try:
        with AnyReader([path], default_typestore=typestore()) as reader:
            wanted = _check_topics(reader, mapping, path)
            content = content_digest(reader)
            _check_counts(path, content, mapping)
            source = label_source(mapping, {c.topic for c in wanted})
            assembler = FrameAssembler(mapping, source)
            frames: list[Frame] = []
            for conn, log_ns, raw in reader.messages(connections=wanted):
                msg = reader.deserialize(raw, conn.msgtype)
                frames.extend(assembler.push(conn.topic, conn.msgtype, msg, log_ns))
            frames.extend(assembler.finish())
            custom = _custom_data(reader)
    except SourceError as e:
        raise BagError(f"{path}: {e}") from None
    except BagError:
        raise
    except Exception as e:  # rosbags raises many kinds on a truncated or corrupt bag
        kind = "unreadable" if not isinstance(e, AnyReaderError | FileNotFoundError) else "bad"
        raise BagError(f"{path}: (bag): {kind} bag ({type(e).__name__}: {e})") from None
    return imported_run(path, mapping, assembler, frames, _identity(path, custom), content)


def imported_run(path: Path, mapping: Mapping, assembler: FrameAssembler, frames: list[Frame],
                 identity: dict[str, Any], content: Content,
                 software: str = SOFTWARE) -> ImportedRun:
    """A recording's converted frames as a run, with its notes; BagError if it has none."""
    if not frames:
        raise BagError(f"{path}: (bag): no frame: the required topics never overlap in time")
    notes = []
    if assembler.empty_object_frames:
        notes.append(f"{path}: {mapping.topics.objects}: empty object list in "
                     f"{assembler.empty_object_frames} of {len(frames)} frames")
    if assembler.recovered_plan_times:
        notes.append(f"{path}: {mapping.topics.trajectory}: all-zero time_from_start in "
                     f"{assembler.recovered_plan_times} trajectories, times rebuilt from arc "
                     "length over speed")
    source = assembler.label_source
    if source == UNLABELLED:
        notes.append(f"{path}: (bag): no ground truth ({mapping.topics.collision or '-'}, "
                     f"{mapping.topics.ground_truth_objects or '-'}): imported unlabelled")
    metadata = run_metadata(identity, content, assembler, frames, source, software)
    return ImportedRun(path, metadata, frames, notes)
