"""Where evoeye keeps its data: one data root, resolved once, with a named folder per stage.

The command line (`evoeye.cli`) and the flows (`flows/`) resolve the root once, from `--root`,
`$EVOEYE_HOME` or the default; everything inside `evoeye` takes the resolved `DataRoot`.

Layout under the root (default `./evoeye-data`, or `$EVOEYE_HOME`, or `--root`):

    runs/<logical_scenario>/<batch>/<scenario_id>.mcap  one MCAP log per run (`*.tmp`: unfinished)
    warehouse/<table>/logical_scenario=…/batch=…/*.parquet  append-only Parquet tables
    warehouse/evoeye.duckdb                              views over the Parquet, for DuckDB's CLI
    quarantine/…                                         logs that could not be read, and why
    monitors/<version>/{model.pt,card.json}              trained monitor versions (cards)
    replays/<log>.<monitor>.risk.mcap                    logs with a monitor's risk (`replay`)
    supervision/<logical_scenario>/<batch>/<key>/…       supervised runs (`supervise`)
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

ENV_VAR = "EVOEYE_HOME"
DEFAULT_ROOT = Path("evoeye-data")
LOG_SUFFIX = ".mcap"
PLAIN_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


class MissingRootError(FileNotFoundError):
    """A command that reads data was pointed at a data root that does not exist."""


class BadNameError(ValueError):
    """A name that becomes a folder (a batch) is not a plain name."""


def check_batch_name(name: str) -> str:
    """`name` if it is a plain folder name (letters, digits, '.', '_', '-'; no '..', no '/'),
    else BadNameError: a batch name must never lead a log outside its scenario's folder."""
    if not isinstance(name, str) or not PLAIN_NAME.fullmatch(name) or ".." in name:
        raise BadNameError(f"batch name {name!r} is not a plain name (letters, digits, '.', "
                           "'_', '-'; starting with a letter or digit; no '..')")
    return name


@dataclass(frozen=True)
class DataRoot:
    """The data root and the folders inside it; nothing is created until a writer asks."""

    path: Path

    @classmethod
    def resolve(cls, root: str | os.PathLike[str] | None = None) -> DataRoot:
        """An explicit root wins, then $EVOEYE_HOME, then ./evoeye-data; made absolute (symlinks
        are kept, so `runs/` may be a link to another disk)."""
        chosen = root if root is not None else os.environ.get(ENV_VAR) or DEFAULT_ROOT
        return cls(Path(os.path.abspath(Path(chosen).expanduser())))

    @classmethod
    def existing(cls, root: str | os.PathLike[str] | None = None) -> DataRoot:
        """Like `resolve`, for readers: MissingRootError naming the root if it is not a folder."""
        data = cls.resolve(root)
        if not data.path.is_dir():
            raise MissingRootError(f"no data root at {data.path}")
        return data

    @property
    def runs(self) -> Path:
        return self.path / "runs"

    @property
    def warehouse(self) -> Path:
        return self.path / "warehouse"

    @property
    def duckdb_file(self) -> Path:
        return self.warehouse / "evoeye.duckdb"

    @property
    def writer_lock(self) -> Path:
        """The file a warehouse writer holds an exclusive lock on."""
        return self.warehouse / ".writer.lock"

    @property
    def quarantine(self) -> Path:
        return self.path / "quarantine"

    @property
    def monitors(self) -> Path:
        return self.path / "monitors"

    @property
    def replays(self) -> Path:
        """Run logs copied with a monitor's risk channel (`evoeye replay`); never ingested."""
        return self.path / "replays"

    @property
    def supervision(self) -> Path:
        """Supervised re-simulations of batches (`evoeye supervise`); never ingested."""
        return self.path / "supervision"

    @property
    def reports(self) -> Path:
        return self.path / "reports"

    def table_dir(self, table: str) -> Path:
        return self.warehouse / table

    def batch_dir(self, logical_scenario: str, batch: str) -> Path:
        """The folder of one batch's logs (BadNameError for a batch that is not plain)."""
        return self.runs / logical_scenario / check_batch_name(batch)

    def run_log(self, logical_scenario: str, batch: str, scenario_id: str) -> Path:
        """Where the MCAP log of one run lives."""
        return self.batch_dir(logical_scenario, batch) / f"{scenario_id}{LOG_SUFFIX}"

    def relative(self, path: Path) -> str:
        """`path` relative to the root, POSIX-style (as stored in the warehouse)."""
        return Path(os.path.abspath(path)).relative_to(self.path).as_posix()
