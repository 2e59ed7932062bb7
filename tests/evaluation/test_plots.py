"""interval_chart: each row's estimate and CI where the axis says they are."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from evoeye.evaluation.plots import interval_chart, standalone


def _svg(text: str) -> ET.Element:
    return ET.fromstring(text.replace("<svg ", '<svg xmlns="http://www.w3.org/2000/svg" ', 1))


NS = "{http://www.w3.org/2000/svg}"


def _axis(root: ET.Element) -> dict[float, float]:
    """Tick value → x pixel, from the tick labels under the plotting area."""
    ticks = {}
    for t in root.iter(f"{NS}text"):
        try:
            ticks[float(t.text)] = float(t.get("x"))
        except (TypeError, ValueError):
            continue
    return ticks


def test_error_bars_sit_at_their_values_on_the_axis() -> None:
    rows = [("FusionMonitor − context-only <b>", 3.0, -1.0, 7.5), ("no interval", 12.0, None, None),
            ("nothing", None, None, None)]
    root = _svg(interval_chart(rows, title="t", xlabel="x", reference=0.0))
    ticks = _axis(root)
    (lo_v, lo_x), (hi_v, hi_x) = min(ticks.items()), max(ticks.items())
    to_x = lambda v: lo_x + (v - lo_v) / (hi_v - lo_v) * (hi_x - lo_x)  # noqa: E731
    bars = [e for e in root.iter(f"{NS}line") if e.get("data-interval")]
    assert len(bars) == 1  # the row without an interval has none
    assert float(bars[0].get("x1")) == pytest.approx(to_x(-1.0), abs=0.1)
    assert float(bars[0].get("x2")) == pytest.approx(to_x(7.5), abs=0.1)
    dots = [e for e in root.iter(f"{NS}circle")]
    assert [float(d.get("data-estimate")) for d in dots] == [3.0, 12.0]
    assert float(dots[0].get("cx")) == pytest.approx(to_x(3.0), abs=0.1)
    assert float(dots[1].get("cx")) == pytest.approx(to_x(12.0), abs=0.1)
    dashed = [e for e in root.iter(f"{NS}line") if e.get("stroke-dasharray")]
    assert float(dashed[0].get("x1")) == pytest.approx(to_x(0.0), abs=0.1)
    assert lo_v <= -1.0 and hi_v >= 12.0  # every value inside the axis
    labels = [t.text for t in root.iter(f"{NS}text")]
    assert "FusionMonitor − context-only <b>" in labels and "nothing" in labels  # escaped
    # the longest label fits left of the plotting area
    frame = next(root.iter(f"{NS}rect"))
    assert float(frame.get("x")) >= 7 * len(rows[0][0]) - 10


def test_an_empty_chart_still_renders() -> None:
    root = _svg(interval_chart([], title="empty", xlabel="x"))
    assert root.get("aria-label") == "empty"


def test_a_standalone_chart_is_an_svg_file_with_the_same_marks() -> None:
    chart = interval_chart([("a", 10.0, 5.0, 15.0)], title="t", xlabel="x")
    root = ET.fromstring(standalone(chart))  # parses as a file: the namespace is declared
    assert root.tag == f"{NS}svg" and root.find(f"{NS}style").text.startswith("svg{font:")
    inline = _svg(chart)
    assert [e.attrib for e in root.iter(f"{NS}circle")] == \
        [e.attrib for e in inline.iter(f"{NS}circle")]
