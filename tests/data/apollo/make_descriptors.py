"""Write schemas/external/apollo/apollo.desc: the protobuf descriptors of the Apollo messages
evoeye reads and writes, and of the cyber record container, as one FileDescriptorSet.

The descriptors are those compiled into apollo-modules 11.0.0 (Apollo's common_msgs) and
cyber-record 0.1.13 (cyber/proto/record.proto), which pin protobuf 3.20 and < 6 and so cannot
be installed beside evoeye's protobuf 7 (docs/apollo.md). Run it in a scratch venv:

    python -m venv /tmp/apollo && /tmp/apollo/bin/pip install protobuf==7.36.2
    /tmp/apollo/bin/pip install --no-deps apollo-modules==11.0.0 cyber-record==0.1.13
    /tmp/apollo/bin/python tests/data/apollo/make_descriptors.py

Each file comes after the files it imports, so a descriptor pool can add them in order.
"""

from __future__ import annotations

import importlib
from pathlib import Path

OUT = Path(__file__).resolve().parents[3] / "schemas" / "external" / "apollo" / "apollo.desc"
ROOTS = (  # the messages evoeye maps (docs/apollo.md), and the record container
    "apollo_modules.modules.common_msgs.localization_msgs.localization_pb2",
    "apollo_modules.modules.common_msgs.chassis_msgs.chassis_pb2",
    "apollo_modules.modules.common_msgs.perception_msgs.perception_obstacle_pb2",
    "apollo_modules.modules.common_msgs.prediction_msgs.prediction_obstacle_pb2",
    "apollo_modules.modules.common_msgs.planning_msgs.planning_pb2",
    "apollo_modules.modules.common_msgs.control_msgs.control_cmd_pb2",
    "cyber_record.cyber.proto.record_pb2",
    "cyber_record.cyber.proto.proto_desc_pb2",
)


def descriptor_set() -> bytes:
    from google.protobuf import descriptor_pb2

    out, seen = descriptor_pb2.FileDescriptorSet(), set()

    def add(fd) -> None:  # noqa: ANN001 - a FileDescriptor
        if fd.name in seen:
            return
        for dep in fd.dependencies:
            add(dep)
        seen.add(fd.name)
        fd.CopyToProto(out.file.add())

    for name in ROOTS:
        add(importlib.import_module(name).DESCRIPTOR)
    return out.SerializeToString(deterministic=True)


if __name__ == "__main__":
    OUT.write_bytes(descriptor_set())
    print(OUT, OUT.stat().st_size, "bytes")
