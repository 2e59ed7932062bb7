"""Report cells and tables: how every evoeye report writes a figure (docs/reports.md).

Rates are percentages with one decimal, times in seconds, a figure's 95 % interval follows it
in parentheses in the same cell ("75.0 (40.9–92.9)"). A table must fit the Prefect artifact
view and a laptop's browser without scrolling sideways: at most `MAX_COLUMNS` columns and
`MAX_WIDTH_CHARS` characters of its widest row.
"""

from __future__ import annotations

from dataclasses import dataclass
from html import escape

DASH = "–"
UNREACHABLE = "n/r"  # the operating point's target FPR was unreachable on validation
UNREACHABLE_NOTE = ("n/r: the target FPR is unreachable for this monitor: more than that share "
                    "of the validation negatives tie at its top score, so no threshold meets "
                    "the target with any alarm (its rates there are not measured).")
MAX_COLUMNS = 9  # narrow numeric columns; the width decides
MAX_WIDTH_CHARS = 100  # cells of the widest row plus 3 per column, as Markdown lays them out


def pct(x: float | None) -> str:
    """A rate as a percentage with one decimal ('–' if undefined)."""
    return DASH if x is None else f"{100 * x:.1f}"


def rate(point: dict, key: str) -> str:
    """A rate of one operating point (`PRF.to_dict()`) in %, 'n/r' where its target FPR was
    unreachable."""
    return pct(point[key]) if point.get("reachable", True) else UNREACHABLE


def any_unreachable(reports: list[dict]) -> bool:
    """Whether some monitor of these reports has a target FPR it could not reach."""
    return any(not ok for r in reports for m in r["monitors"]
               for ok in m.get("reachable", {}).values())


def _number(x: float, unit: str) -> str:
    return f"{100 * x:.1f}" if unit == "%" else f"{x:.1f}"


def with_ci(est: dict, unit: str = "") -> str:
    """An `Estimate.to_dict()` as "value (low–high)"; unit "%" shows a proportion in %.

    No interval: the value alone ("n = 1" when one run defines it); with no event at all
    (method "poisson-zero") the upper bound: "0 (≤ 3.7)"."""
    if est["value"] is None:
        return DASH
    value = _number(est["value"], unit)
    if est["method"] == "poisson-zero":
        return f"0 (≤ {_number(est['high'], unit)})"
    if est["low"] is None:
        return f"{value} (n = {est['n']})"
    return f"{value} ({_number(est['low'], unit)}–{_number(est['high'], unit)})"


@dataclass
class Table:
    """Header and rows of text cells; section rows have a single cell."""

    header: list[str]
    rows: list[list[str]]

    def markdown(self) -> str:
        lines = ["| " + " | ".join(self.header) + " |",
                 "|" + "|".join(["---"] + ["---:"] * (len(self.header) - 1)) + "|"]
        for row in self.rows:
            cells = row if len(row) > 1 else [f"**{row[0]}**"] + [""] * (len(self.header) - 1)
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)

    def html(self) -> str:
        head = "".join(f"<th>{escape(h)}</th>" for h in self.header)
        body = []
        for row in self.rows:
            if len(row) == 1:
                body.append(f'<tr class="sec"><td colspan="{len(self.header)}">'
                            f"{escape(row[0])}</td></tr>")
            else:
                body.append("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in row) + "</tr>")
        return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"

    def width_chars(self) -> int:
        """Characters of the widest column layout: each column as wide as its widest cell
        (header included; section rows span the table and are left out), plus 3 per column."""
        cells = [self.header] + [r for r in self.rows if len(r) > 1]
        return sum(max(len(row[i]) for row in cells) + 3 for i in range(len(self.header)))

    def fits(self) -> bool:
        """Whether it fits the Prefect artifact view without scrolling sideways."""
        return len(self.header) <= MAX_COLUMNS and self.width_chars() <= MAX_WIDTH_CHARS
