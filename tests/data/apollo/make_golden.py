"""Write the golden Apollo record (tests/data/apollo/golden.record.xz): the stored run log of
tests/data/autoware/make_golden.py (the first second of a simulated highway-cut-in run), every
channel on the 20 Hz clock, with its ground truth, xz-compressed (the record itself is mostly
the descriptors each channel carries).

    .venv/bin/python tests/data/apollo/make_golden.py

tests/sources/test_apollo_golden.py writes it again and compares the record's bytes, so a
change of the exporter's conventions shows as a changed golden record in review.
"""

from __future__ import annotations

import importlib.util
import lzma
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
GOLDEN = HERE / "golden.record.xz"


def golden_record(out_dir: Path) -> Path:
    """The golden record `<out_dir>/golden.record` (not compressed)."""
    from evoeye.sources.apollo.export import record_messages
    from evoeye.sources.apollo.record import write_record
    from evoeye.sources.autoware.export import RATES

    spec = importlib.util.spec_from_file_location(
        "make_golden_autoware", HERE.parent / "autoware" / "make_golden.py")
    autoware = sys.modules.setdefault(spec.name, importlib.util.module_from_spec(spec))
    spec.loader.exec_module(autoware)
    with tempfile.TemporaryDirectory() as tmp:
        _, messages = record_messages(autoware.golden_log(Path(tmp)), RATES["lossless"])
    return write_record(Path(out_dir) / "golden.record", messages)


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as tmp:
        GOLDEN.write_bytes(lzma.compress(golden_record(Path(tmp)).read_bytes(), preset=9))
    print(GOLDEN, GOLDEN.stat().st_size, "bytes")
