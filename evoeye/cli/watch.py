"""`evoeye watch`: the monitor beside a running Autoware stack, following its recording."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from evoeye.cli.app import app
from evoeye.cli.autoware import MappingOpt, load_mapping_option
from evoeye.cli.defaults import TARGET_FPRS, WARNING_K
from evoeye.cli.errors import UserError
from evoeye.cli.monitor import MonitorOpt, RootOpt
from evoeye.cli.output import err
from evoeye.paths import DataRoot


@app.command("watch")
def watch_command(
    path: Annotated[Path, typer.Argument(
        help="An MCAP bag being recorded, or a folder of split bags (rosbag2); or an Apollo "
             "cyber record, or a folder of split records.")],
    monitor: MonitorOpt,
    root: RootOpt = None,
    output: Annotated[Path | None, typer.Option(
        "--out", help="Risk MCAP to write (default: <root>/replays/<bag>.<monitor>.watch.mcap).")
    ] = None,
    mapping: MappingOpt = None,
    fpr: Annotated[float, typer.Option(help=f"Alarm threshold's target FPR, one of "
                                       f"{TARGET_FPRS}.")] = TARGET_FPRS[0],
    consecutive: Annotated[int, typer.Option(
        "--consecutive", min=1, help="Frames above the threshold before the alarm (K; as "
        "`evoeye replay` and the reports count a warning).")] = WARNING_K,
    idle_s: Annotated[float, typer.Option(
        "--idle-s", min=0.0, help="Stop after this long without a new message.")] = 5.0,
) -> None:
    """Score each frame of a recording as it is written: risk and alarms as JSON lines on
    stdout and in a risk MCAP (Foxglove: plot /monitor/risk.score). No ROS needed."""
    from evoeye.monitor.registry import load_monitor
    from evoeye.monitor.runtime import RuntimeMonitor
    from evoeye.monitor.watch import Watch
    from evoeye.sources.apollo.follow import is_record
    from evoeye.sources.autoware.frames import SourceError

    data = DataRoot.existing(root)
    assembler, messages = (_apollo if is_record(path) else _autoware)(path, mapping, idle_s)
    fusion = load_monitor(data, monitor)
    if output is None:
        data.replays.mkdir(parents=True, exist_ok=True)
        output = data.replays / f"{path.stem}.{monitor}.watch.mcap"
    runtime = RuntimeMonitor(fusion, fpr=fpr, consecutive=consecutive)

    def emit(line: bytes) -> None:
        sys.stdout.write(line.decode() + "\n")
        sys.stdout.flush()

    watch = Watch(runtime, output, emit)
    try:
        for topic, msgtype, msg, log_ns in messages:
            for frame in assembler.push(topic, msgtype, msg, log_ns):
                watch.step(frame.messages, frame.t_ns)
        for frame in assembler.finish():
            watch.step(frame.messages, frame.t_ns)
    except SourceError as exc:
        raise UserError(f"{path}: {exc}", "check the topics (--mapping, docs/autoware.md)") \
            from exc
    except KeyboardInterrupt:
        pass
    finally:
        watch.close()
    alarms = sum(s.alarm for s in watch.states)
    err().print(f"{len(watch.states)} frames, {alarms} alarm frames; wrote {output}")


def _autoware(path: Path, mapping: Path | None, idle_s: float):  # noqa: ANN202 - heavy types
    """The frame assembler and the followed messages of a rosbag2 MCAP recording."""
    from evoeye.log.records import UNLABELLED
    from evoeye.sources.autoware.follow import follow
    from evoeye.sources.autoware.frames import FrameAssembler

    assembler = FrameAssembler(load_mapping_option(mapping), UNLABELLED)  # needs no label
    return assembler, follow(path, topics=set(assembler.roles), idle_s=idle_s)


def _apollo(path: Path, mapping: Path | None, idle_s: float):  # noqa: ANN202 - heavy types
    """… of an Apollo cyber record (a --mapping file overrides Apollo's defaults)."""
    from evoeye.log.records import UNLABELLED
    from evoeye.sources.apollo import convert
    from evoeye.sources.apollo.follow import RecordFollower, record_splits
    from evoeye.sources.apollo.run import apollo_mapping
    from evoeye.sources.autoware.follow import follow
    from evoeye.sources.autoware.frames import FrameAssembler

    assembler = FrameAssembler(load_mapping_option(mapping, apollo_mapping()), UNLABELLED,
                               lookup=convert.converter, stamp=convert.stamp_ns)
    return assembler, follow(path, topics=set(assembler.roles), idle_s=idle_s,
                             follower=RecordFollower, split_files=record_splits)
