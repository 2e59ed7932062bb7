"""Apollo's message classes, built at run time from vendored descriptors, not generated code.

`schemas/external/apollo/apollo.desc` is one FileDescriptorSet: Apollo's common_msgs as
apollo-modules 11.0.0 compiled them (localization, chassis, perception and prediction
obstacles, planning, control and what they import) and cyber's record container
(cyber/proto/record.proto, proto_desc.proto) as cyber-record 0.1.13 did. Both packages pin a
protobuf evoeye cannot have beside its own (docs/apollo.md), so their descriptors are vendored
and the classes come from the installed protobuf runtime (`message_factory.GetMessages`): no
generated code, so no gencode and runtime versions to match. A record's own descriptors (each
channel carries its type's, with their imports) build the classes of that record
(`classes_from_proto_desc`).
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

DESCRIPTORS = Path(__file__).resolve().parents[3] / "schemas" / "external" / "apollo" / \
    "apollo.desc"


def _classes(files: list[Any]) -> dict[str, type]:
    """Full message name → class, of FileDescriptorProtos given after their imports."""
    from google.protobuf import descriptor_pool, message_factory

    pool = descriptor_pool.DescriptorPool()
    for f in files:
        pool.Add(f)
    return message_factory.GetMessages(files, pool=pool)


@cache
def vendored() -> dict[str, type]:
    """Full message name (`apollo.localization.LocalizationEstimate`) → class."""
    from google.protobuf import descriptor_pb2

    fds = descriptor_pb2.FileDescriptorSet.FromString(DESCRIPTORS.read_bytes())
    return _classes(list(fds.file))


def vendored_files() -> dict[str, Any]:
    """File name → FileDescriptorProto of the vendored set, in import order."""
    from google.protobuf import descriptor_pb2

    fds = descriptor_pb2.FileDescriptorSet.FromString(DESCRIPTORS.read_bytes())
    return {f.name: f for f in fds.file}


def record_type(name: str) -> type:
    """A message class of cyber's record container (`Header`, `Channel`, `ChunkBody`, …)."""
    return vendored()[f"apollo.cyber.proto.{name}"]


def proto_desc(message_type: str) -> bytes:
    """A cyber ProtoDesc of `message_type` — its file's descriptor and, recursively, its
    imports' — as a recorder writes it on a channel."""
    files = vendored_files()
    by_message = {f"{f.package}.{m.name}": f for f in files.values() for m in f.message_type}
    desc_cls = record_type("ProtoDesc")

    def build(file: Any) -> Any:
        out = desc_cls(desc=file.SerializeToString())
        for dep in file.dependency:
            out.dependencies.append(build(files[dep]))
        return out

    return build(by_message[message_type]).SerializeToString()


def classes_from_proto_desc(raw: bytes) -> dict[str, type]:
    """The message classes a channel's ProtoDesc defines (its file and its imports)."""
    from google.protobuf import descriptor_pb2

    desc_cls = record_type("ProtoDesc")
    files: dict[str, Any] = {}

    def walk(desc: Any) -> None:
        for dep in desc.dependencies:
            walk(dep)
        f = descriptor_pb2.FileDescriptorProto.FromString(desc.desc)
        files.setdefault(f.name, f)

    walk(desc_cls.FromString(raw))
    return _classes(list(files.values()))
