"""FusionMonitor inference cost on CPU: batch-1 latency per context, throughput, ONNX Runtime.

Targets: batch-1 latency ≤ 0.25 ms per context (the paper reports 2.49 ms on CPU), and
`RuntimeMonitor.step` ≤ 0.3 ms per frame (features from the messages + context + model; its
ratio to `score_batch` is printed from the same run). Measured on windows of the warehouse under
`--root` (L from the monitor; without `--root`, `--runs` synthetic runs shaped like the ADS's are
written and ingested in a temporary folder), one intra-op thread:

  torch eager      FusionNet forward + sigmoid under torch.inference_mode, inputs ready
  torch traced     the same, TorchScript-traced (what FusionMonitor runs)
  FusionMonitor    `score_batch`: the traced net plus tensor → numpy (the Monitor path)
  ONNX Runtime     the exported model, one session thread (`onnx_session`, what
                   RuntimeMonitor runs)
  features         one frame of ADS messages → its monitor inputs (`MessageSignals` through the
                   warehouse's feature code), alone
  RuntimeMonitor   `step(messages)`: one frame of ADS messages → features → context → score
                   (ONNX Runtime reading the context buffers in place)
  throughput       windows / s at batch 1024: torch eager, traced and ONNX Runtime

Latencies are medians (and p99) over `--calls` calls after `--warmup` calls. The monitor is
`--monitor VERSION` or the root's newest version; with none, an untrained network with
normalisers fitted on the windows (the cost does not depend on the weights).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections.abc import Callable

import numpy as np
import onnxruntime as ort
import torch

from benchmarks.bench_warehouse import write_logs
from benchmarks.machine import describe
from evoeye.monitor.export import OUTPUT, onnx_session
from evoeye.monitor.fusion import FusionMonitor, net_inputs, traced
from evoeye.monitor.model import INPUTS, FusionConfig, FusionNet
from evoeye.monitor.protocol import Thresholds
from evoeye.monitor.registry import list_versions, load_monitor
from evoeye.monitor.replay import log_frames
from evoeye.monitor.runtime import RuntimeMonitor
from evoeye.paths import DataRoot
from evoeye.store import Warehouse, ingest, load_windows
from evoeye.store.features import frame_features
from evoeye.store.records import MessageSignals

TARGET_MS = 0.25
STEP_TARGET_MS = 0.3
SYNTHETIC_FRAMES = 400  # frames per synthetic run when no --root is given


def timed(fn: Callable[[], object], calls: int, warmup: int) -> tuple[float, float]:
    """(median, p99) wall milliseconds of one call."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(calls):
        t0 = time.perf_counter_ns()
        fn()
        times.append((time.perf_counter_ns() - t0) / 1e6)
    return statistics.median(times), float(np.percentile(times, 99))


def pick_monitor(root: DataRoot, version: str | None, windows_of: Callable[[int], object]
                 ) -> FusionMonitor:
    version = version or next(iter(reversed(list_versions(root))), None)
    if version is not None:
        return load_monitor(root, version)
    net = FusionNet(FusionConfig())
    windows = windows_of(net.config.context_len)
    net.fit_normalizers(windows.features)
    return FusionMonitor(net.eval(), "untrained", Thresholds({0.05: 0.5}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", default=None,
                    help="data root with an ingested warehouse (default: synthetic runs)")
    ap.add_argument("--monitor", default=None, help="version (default: the newest)")
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--warmup", type=int, default=200)
    ap.add_argument("--runs", type=int, default=8, help="runs whose windows are used")
    args = ap.parse_args()
    torch.set_num_threads(1)
    if args.root is not None:
        measure(args, DataRoot.resolve(args.root))
        return
    with tempfile.TemporaryDirectory(prefix="bench-monitor-") as tmp:
        root = DataRoot.resolve(tmp)
        write_logs(root, args.runs, SYNTHETIC_FRAMES)
        ingest(root)
        measure(args, root)


def measure(args: argparse.Namespace, root: DataRoot) -> None:
    runs = Warehouse(root).sql(
        f"SELECT scenario_id, log_path FROM scenarios WHERE status = 'ok' "
        f"ORDER BY scenario_id LIMIT {int(args.runs)}").to_pylist()
    ids = [r["scenario_id"] for r in runs]
    monitor = pick_monitor(root, args.monitor, lambda L: load_windows(root, ids, context_len=L))
    windows = load_windows(root, ids, context_len=monitor.context_len)
    print(f"Machine: {describe()}")
    print(f"Monitor: {monitor.version}, L = {monitor.context_len}, "
          f"{monitor.net.n_parameters():,} parameters; {len(windows):,} windows of "
          f"{len(ids)} runs; torch {torch.__version__}, onnxruntime {ort.__version__}, "
          f"1 thread\n")
    net = monitor.net.eval()
    rng = np.random.default_rng(0)
    one = windows.batch(np.array([int(rng.integers(len(windows)))]))
    x1 = net_inputs(one)
    big_index = np.sort(rng.choice(len(windows), min(1024, len(windows)), replace=False))
    big = net_inputs(windows.batch(big_index))

    graph = traced(net)

    def torch_net(x=x1, forward=net) -> torch.Tensor:
        with torch.inference_mode():
            return torch.sigmoid(forward(*x))

    rows = []
    rows.append(("torch eager, batch 1", *timed(torch_net, args.calls, args.warmup)))
    rows.append(("torch traced, batch 1",
                 *timed(lambda: torch_net(x1, graph), args.calls, args.warmup)))
    rows.append(("FusionMonitor.score_batch, batch 1",
                 *timed(lambda: monitor.score_batch(one), args.calls, args.warmup)))
    session = onnx_session(monitor, threads=1)
    feed1 = {name: t.numpy() for name, t in zip(INPUTS, x1, strict=True)}
    feed_big = {name: t.numpy() for name, t in zip(INPUTS, big, strict=True)}
    rows.append(("ONNX Runtime, batch 1",
                 *timed(lambda: session.run([OUTPUT], feed1), args.calls, args.warmup)))
    frames = log_frames(root.path / runs[0]["log_path"])
    repeats = 1 + (args.calls + args.warmup) // len(frames)
    stream = iter(frames * repeats)
    features = timed(lambda: frame_features(MessageSignals(next(stream))), args.calls,
                     args.warmup)
    runtime = RuntimeMonitor(monitor, threshold=0.5)
    stream = iter(frames * repeats)
    step = timed(lambda: runtime.step(next(stream)), args.calls, args.warmup)

    print("| batch-1 latency per context | median ms | p99 ms | target ≤ 0.25 ms |")
    print("|---|---|---|---|")
    for name, median, p99 in rows:
        print(f"| {name} | {median:.4f} | {p99:.4f} | {'yes' if median <= TARGET_MS else 'no'} |")
    model_ms = rows[2][1]  # FusionMonitor.score_batch
    print("\n| one ADS frame | median ms | p99 ms | × score_batch | target ≤ 0.3 ms |")
    print("|---|---|---|---|---|")
    print(f"| features (MessageSignals → frame_features) | {features[0]:.4f} | {features[1]:.4f} "
          f"| {features[0] / model_ms:.2f} | — |")
    print(f"| RuntimeMonitor.step (features + context + model) | {step[0]:.4f} | {step[1]:.4f} "
          f"| {step[0] / model_ms:.2f} | {'yes' if step[0] <= STEP_TARGET_MS else 'no'} |")

    n = len(big_index)
    big_calls = max(20, args.calls // 50)
    print(f"\n| throughput, batch {n} | ms per batch | windows / s |")
    print("|---|---|---|")
    for name, fn in (("torch eager", lambda: torch_net(big)),
                     ("torch traced", lambda: torch_net(big, graph)),
                     ("ONNX Runtime", lambda: session.run([OUTPUT], feed_big))):
        ms, _ = timed(fn, big_calls, 5)
        print(f"| {name} | {ms:.2f} | {n / ms * 1e3:,.0f} |")


if __name__ == "__main__":
    main()
