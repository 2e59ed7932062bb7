"""`evoeye watch` per-frame cost: can it keep up with an Autoware bag recorded at 20 Hz?

A simulated highway-cut-in run (20 s, 400 frames) is exported as an Autoware bag at realistic
rates (odometry 50 Hz, objects, predictions and planning 10 Hz, control 33 Hz: ≈ 2 900
messages). Its messages are then fed in receive order through what `evoeye watch` runs —
CDR decoding (rosbags), `FrameAssembler`, `RuntimeMonitor.step` (features + ONNX Runtime) and
the risk sink (JSON line + MCAP) — and timed per frame:

  latency      from the closing message (the odometry stamped after the frame) to the frame's
               risk written: decode + assemble + score
  work         everything the frame costs: every message decoded since the previous frame,
               plus the above (must stay well under the 50 ms frame period to keep up)

Target: p99 latency ≤ 10 ms. Times are wall (perf_counter) and CPU (process_time) per frame;
the monitor is an untrained network (its cost does not depend on the weights).
"""

from __future__ import annotations

import argparse
import io
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader

from benchmarks.machine import describe
from evoeye.log import write_episode
from evoeye.log.records import UNLABELLED
from evoeye.monitor.fusion import FusionMonitor
from evoeye.monitor.model import FusionConfig, FusionNet
from evoeye.monitor.protocol import Thresholds
from evoeye.monitor.runtime import RuntimeMonitor
from evoeye.monitor.watch import RiskSink, frame_messages
from evoeye.scenarios import get_scenario
from evoeye.sim.runner import run_episode, run_spec
from evoeye.sources.autoware.config import Mapping
from evoeye.sources.autoware.export import export_run
from evoeye.sources.autoware.frames import FrameAssembler
from evoeye.sources.autoware.typestore import typestore
from evoeye.store import load_windows

TARGET_MS = 10.0


def _monitor(log: Path) -> FusionMonitor:
    """An untrained FusionMonitor with normalisers fitted on the run's own frames."""
    from evoeye.paths import DataRoot
    from evoeye.store import ingest

    with tempfile.TemporaryDirectory() as tmp:
        root = DataRoot.resolve(Path(tmp) / "data")
        dest = root.run_log("highway-cut-in", "bench", "r")
        dest.parent.mkdir(parents=True)
        dest.write_bytes(log.read_bytes())
        ingest(root)
        net = FusionNet(FusionConfig())
        net.fit_normalizers(load_windows(root, context_len=net.config.context_len).features)
    return FusionMonitor(net.eval(), "untrained", Thresholds({0.05: 0.5}))


def measure(bag: Path, monitor: FusionMonitor) -> dict[str, np.ndarray]:
    """Per-frame latency and work (wall and CPU ms) of the watch loop over the bag."""
    with AnyReader([bag]) as reader:
        raw = [(c.topic, c.msgtype, data, ns) for c, ns, data in reader.messages()]
    store = typestore()
    assembler = FrameAssembler(Mapping(), UNLABELLED)
    runtime = RuntimeMonitor(monitor)
    sink = RiskSink(io.BytesIO(), lambda line: None, monitor.version)
    out: dict[str, list[float]] = {k: [] for k in ("latency", "latency_cpu", "work",
                                                   "work_cpu")}
    since_wall, since_cpu = 0.0, 0.0  # work of the messages since the last frame
    for topic, msgtype, data, ns in raw:
        w0, c0 = time.perf_counter(), time.process_time()
        msg = store.deserialize_cdr(data, msgtype)
        frames = list(assembler.push(topic, msgtype, msg, ns))
        for frame in frames:
            sink.write(runtime.step(frame_messages(frame.messages)), frame.t_ns)
        wall, cpu = (time.perf_counter() - w0) * 1e3, (time.process_time() - c0) * 1e3
        if frames:
            out["latency"].append(wall)
            out["latency_cpu"].append(cpu)
            out["work"].append(since_wall + wall)
            out["work_cpu"].append(since_cpu + cpu)
            since_wall, since_cpu = 0.0, 0.0
        else:
            since_wall, since_cpu = since_wall + wall, since_cpu + cpu
    return {k: np.array(v[5:]) for k, v in out.items()}  # the first frames warm up ONNX


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    space = get_scenario("highway-cut-in")
    spec = run_spec(space.name, space.sample(np.random.default_rng(args.seed)), args.seed)
    episode = run_episode(spec)
    with tempfile.TemporaryDirectory() as tmp:
        log = write_episode(episode, Path(tmp) / "run.mcap")
        bag = export_run(log, Path(tmp) / "bags", rates="realistic")
        n_msgs = sum(1 for _ in AnyReader([bag]).__enter__().messages())
        result = measure(bag, _monitor(log))
    print(describe())
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} "
          f"{os.getloadavg()[2]:.2f}")
    print(f"{len(episode.frames)} frames, {n_msgs} messages; per frame, ms:")
    print("| per frame | median | p99 | max |")
    print("|---|---|---|---|")
    for name, values in result.items():
        print(f"| {name} | {np.median(values):.2f} | {np.percentile(values, 99):.2f} | "
              f"{values.max():.2f} |")
    p99 = float(np.percentile(result["latency"], 99))
    print(f"p99 latency {p99:.2f} ms: target ≤ {TARGET_MS} ms "
          f"{'met' if p99 <= TARGET_MS else 'NOT met'}")


if __name__ == "__main__":
    main()
