"""`evoeye audit`: is a batch realistic? Kinematics, pass-through, pop-in, careful driver,
attribution shares, collision times and the clock, each against its bound (`verdicts.py`).

Per-run checks are pure functions on a run's ground-truth arrays (`tracks.Tracks`), one module
per family; `summary.audit_root` ties them to the logs and the warehouse; `report` renders.
"""

from evoeye.evaluation.audit.report import markdown_report, report_dir, write_report
from evoeye.evaluation.audit.runs import AuditBounds, NoLogsError, RunAudit, audit_run, find_logs
from evoeye.evaluation.audit.summary import ScenarioAudit, audit_root
from evoeye.evaluation.audit.verdicts import Thresholds, Verdict, bands_of

__all__ = [
    "AuditBounds",
    "NoLogsError",
    "RunAudit",
    "ScenarioAudit",
    "Thresholds",
    "Verdict",
    "bands_of",
    "audit_root",
    "audit_run",
    "find_logs",
    "markdown_report",
    "report_dir",
    "write_report",
]
