"""The ROS 2 message types of an Autoware recording: ROS 2 Humble's plus the vendored Autoware ones.

A bag that embeds its definitions (MCAP; `.db3` from Iron on) is decoded with them alone, so a
bag of older or newer Autoware messages reads as recorded; a bag that embeds none (Humble's
`.db3`) is decoded with this store: ROS 2 Humble's types and the upstream Autoware definitions
vendored in `schemas/external/autoware/` (see its NOTICE and UPSTREAM). `import` (rosbags'
AnyReader) and `watch` (`bag_typestore`, over the schemas of a growing MCAP) choose alike.
Converters are picked by type name (`convert._BY_ROLE`), so the pre-2024 `autoware_auto_*`
names dispatch to the same code.
"""

from __future__ import annotations

from collections.abc import Iterable
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

MSG_DIR = Path(__file__).resolve().parents[3] / "schemas" / "external" / "autoware"


def msg_files() -> dict[str, Path]:
    """Type name (`<package>/msg/<Type>`) → its vendored .msg file."""
    return {f"{p.parent.parent.name}/msg/{p.stem}": p for p in sorted(MSG_DIR.glob("*/msg/*.msg"))}


@cache
def typestore() -> Typestore:
    """ROS 2 Humble's types and the vendored Autoware ones, registered once."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    for name, path in msg_files().items():
        types.update(get_types_from_msg(path.read_text(encoding="utf-8"), name))
    store.register(types)
    return store


IDL_SEPARATOR = "=" * 80 + "\n"  # between the IDL files of one rosbag2 definition


def bag_typestore(definitions: Iterable[tuple[str, str, str]]) -> Typestore:
    """The store a bag decodes with, chosen as rosbags' AnyReader chooses it: the definitions
    the bag embeds — (type name, encoding `ros2msg`/`ros2idl`/`omgidl`, text) — when it has
    any, else `typestore()`."""
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

    types: dict = {}
    for name, encoding, text in definitions:
        if not text:
            continue
        if encoding == "ros2msg":
            types.update(get_types_from_msg(text, name))
        elif text.startswith(f"{IDL_SEPARATOR}IDL: "):
            for part in text.split(IDL_SEPARATOR)[1:]:
                types.update(get_types_from_idl(part.split("\n", 1)[1]))
        else:
            types.update(get_types_from_idl(text))
    if not types:
        return typestore()
    store = get_typestore(Stores.EMPTY)
    store.register(types)
    return store
