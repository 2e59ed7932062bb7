"""Exit codes and user errors: what the `evoeye` command tells a script, and how it says it.

Known user errors (a bad option, a missing root, an unknown monitor, …) print one line and a hint
and exit with `ExitCode.USER_ERROR`; `evoeye --debug …` (or EVOEYE_DEBUG=1) shows the traceback
instead. Anything else is a bug: its traceback is shown and the exit code is 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum


class ExitCode(IntEnum):
    """The exit status of every `evoeye` command."""

    OK = 0
    INTERNAL = 1  # an unexpected error (a bug): the traceback is shown
    USER_ERROR = 2  # bad option or input, missing root, unknown monitor, …; nothing was done
    PARTIAL = 3  # the command finished, but some runs failed or some logs were quarantined
    CHECK_FAILED = 4  # `evoeye audit --strict`: a realism bound is not met
    INTERRUPTED = 130  # Ctrl-C (128 + SIGINT): what was finished is kept, a re-run resumes


EXIT_CODES_HELP = (
    "Exit codes: 0 ok · 2 user error (bad option or input; one line and a hint, "
    "--debug for the traceback) · 3 partly done (some runs failed or some logs were "
    "quarantined) · 4 a checked bound failed (audit --strict) · 130 interrupted (Ctrl-C; "
    "a re-run resumes) · 1 internal error."
)


class UserError(Exception):
    """A mistake the user can fix: shown as one line plus a hint, never as a traceback."""

    def __init__(self, message: str, hint: str = "") -> None:
        super().__init__(message)
        self.hint = hint


ROOT_HINT = "check --root (or EVOEYE_HOME): it must be a folder you can write to"

# Exceptions raised below the CLI that are user errors, by qualified class name (so the CLI
# need not import torch or duckdb to recognise them) → the hint shown under the message.
KNOWN_ERRORS: dict[str, str] = {
    "evoeye.paths.MissingRootError": "create data first: `evoeye simulate …` then "
                                     "`evoeye ingest`, or point --root / EVOEYE_HOME at it",
    "evoeye.paths.BadNameError": "use letters, digits, '.', '_' and '-' only",
    "evoeye.scenarios.space.ScenarioError": "",
    "evoeye.monitor.families.MonitorLoadError": "list the versions with `evoeye monitors`, "
                                                "or train one: `evoeye train --scenario "
                                                "NAME`; a damaged baseline folder can be "
                                                "removed, `evoeye evaluate` trains it again",
    "evoeye.monitor.families.NoMonitorError": "train one first: `evoeye train --scenario NAME`, "
                                              "or name it with --monitor",
    "evoeye.evolve.campaign.state.NoInitialDataError": "simulate and ingest the scenario's initial "
                                                  "runs: `evoeye simulate …`, `evoeye ingest`",
    "evoeye.evolve.campaign.state.MixedProfilesError": "simulate each ADS profile's runs under "
                                                       "a data root of its own (--root)",
    "evoeye.ads.profiles.UnknownProfileError": "",
    "evoeye.evolve.predictability.check.RegimeError": "simulate and ingest runs of the regime "
                                                      "(`evoeye simulate …`, `evoeye ingest`), "
                                                      "or narrow it with --batch / --ads",
    "evoeye.evaluation.audit.runs.NoLogsError": "name a batch the root holds (above), or "
                                                "leave out --scenario and --batch to audit "
                                                "them all; `evoeye simulate …` makes runs",
    "evoeye.results.study.EmptySplitError": "simulate the data with the command (--initial-runs "
                                            "N --test-runs M), or check --test-batch and the "
                                            "shares",
    "evoeye.results.combine.ResultsFileError": "give the results.json (or report folder) of "
                                               "each `evoeye results` run once",
    "evoeye.results.reproduce.PlanError": "give the findings.json `evoeye findings` wrote (or "
                                          "its folder, e.g. docs/results), and --root only "
                                          "for its runs",
    "evoeye.evaluation.supervision.batch.NoRunsError": "simulate the batch first, or check "
                                                       "--scenario, --batch and --root",
    "evoeye.evaluation.supervision.settings.SettingsMismatchError": "move that supervision "
                                                                    "folder aside",
    "evoeye.evaluation.supervision.sweep.ReproductionError": "re-simulate the batch with this "
                                                             "software version",
    "evoeye.evolve.campaign.cluster.ClusterError": "docs/distributed.md says what every "
                                                   "host of a cluster needs",
    "evoeye.evolve.campaign.guard.CampaignBusyError": "",
    "evoeye.store.lock.WarehouseLockedError": "wait for the other writer to finish, then run "
                                              "again",
    "evoeye.store.schema.WarehouseLayoutError": "`evoeye ingest` migrates the previous layout "
                                                "in place; an older one is re-ingested: move "
                                                "warehouse/scenarios, warehouse/frames and "
                                                "warehouse/frame_features aside, then run "
                                                "`evoeye ingest` again",
    "builtins.PermissionError": ROOT_HINT,
    "builtins.NotADirectoryError": ROOT_HINT,
    "builtins.FileExistsError": ROOT_HINT,
    "builtins.IsADirectoryError": ROOT_HINT,
}


@dataclass(frozen=True)
class Explained:
    """A user error as the CLI shows it."""

    message: str
    hint: str


def explain(exc: BaseException) -> Explained | None:
    """The one-line message and hint for a known user error; None for anything else."""
    if isinstance(exc, UserError):
        return Explained(str(exc), exc.hint)
    for cls in type(exc).__mro__:
        hint = KNOWN_ERRORS.get(f"{cls.__module__}.{cls.__qualname__}")
        if hint is not None:
            return Explained(" ".join(str(exc).split()) or type(exc).__name__, hint)
    return None
