"""The vendored Autoware definitions are the upstream files, byte for byte (UPSTREAM names each
file's repository, commit, path and git blob id), `control_time` included."""

from __future__ import annotations

import hashlib

from evoeye.sources.autoware.typestore import MSG_DIR, msg_files, typestore


def _blob_id(data: bytes) -> str:
    """The git blob id of `data` (what `git rev-parse <commit>:<path>` prints)."""
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


def test_every_vendored_definition_is_the_upstream_file() -> None:
    manifest = {}
    for line in (MSG_DIR / "UPSTREAM").read_text().splitlines():
        path, source, blob = line.split()
        manifest[path] = (source, blob)
    vendored = {str(p.relative_to(MSG_DIR)): p for p in msg_files().values()}
    assert sorted(manifest) == sorted(vendored)
    for path, file in vendored.items():
        assert _blob_id(file.read_bytes()) == manifest[path][1], (path, manifest[path][0])


def test_control_carries_control_time_as_upstream() -> None:
    fields = {name: [f for f, _ in typestore().fielddefs[name][1]]
              for name in ("autoware_control_msgs/msg/Control",
                           "autoware_control_msgs/msg/Lateral",
                           "autoware_control_msgs/msg/Longitudinal")}
    assert all(f[:2] == ["stamp", "control_time"] for f in fields.values()), fields
