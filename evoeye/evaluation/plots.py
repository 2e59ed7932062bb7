"""Inline SVG charts for the HTML report: no plotting library, no external resources.

Each function returns one `<svg>` element as text (HTML5 inline SVG needs no namespace URL).
"""

from __future__ import annotations

from collections.abc import Sequence
from html import escape

import numpy as np

PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
           "#17becf", "#7f7f7f", "#bcbd22")
WIDTH, HEIGHT = 420, 340
MARGIN = {"left": 52, "right": 14, "top": 30, "bottom": 46}
LABEL_ROOM_MAX = 260  # px left of an interval chart for its row labels


def _color(i: int) -> str:
    return PALETTE[i % len(PALETTE)]


class _Frame:
    """Maps data coordinates into the plotting area of one chart."""

    def __init__(self, xlim: tuple[float, float], ylim: tuple[float, float],
                 width: int = WIDTH, height: int = HEIGHT) -> None:
        self.xlim, self.ylim, self.width, self.height = xlim, ylim, width, height
        self.x0, self.x1 = MARGIN["left"], width - MARGIN["right"]
        self.y0, self.y1 = height - MARGIN["bottom"], MARGIN["top"]

    def x(self, v: float) -> float:
        lo, hi = self.xlim
        return self.x0 + (v - lo) / ((hi - lo) or 1.0) * (self.x1 - self.x0)

    def y(self, v: float) -> float:
        lo, hi = self.ylim
        return self.y0 - (v - lo) / ((hi - lo) or 1.0) * (self.y0 - self.y1)

    def axes(self, title: str, xlabel: str, ylabel: str, xticks: Sequence[float],
             yticks: Sequence[float], xlabels: Sequence[str] | None = None) -> list[str]:
        out = [
            f'<rect x="{self.x0}" y="{self.y1}" width="{self.x1 - self.x0}" '
            f'height="{self.y0 - self.y1}" fill="#fff" stroke="#999"/>',
            f'<text x="{self.width / 2}" y="18" text-anchor="middle" class="t">'
            f"{escape(title)}</text>",
            f'<text x="{(self.x0 + self.x1) / 2}" y="{self.height - 8}" '
            f'text-anchor="middle">{escape(xlabel)}</text>',
            f'<text x="14" y="{(self.y0 + self.y1) / 2}" text-anchor="middle" '
            f'transform="rotate(-90 14 {(self.y0 + self.y1) / 2})">{escape(ylabel)}</text>',
        ]
        for i, v in enumerate(xticks):
            x = self.x(v)
            text = f"{v:g}" if xlabels is None else xlabels[i]
            out.append(f'<line x1="{x:.1f}" y1="{self.y0}" x2="{x:.1f}" y2="{self.y1}" '
                       'stroke="#eee"/>')
            out.append(f'<text x="{x:.1f}" y="{self.y0 + 15}" text-anchor="middle">'
                       f"{escape(text)}</text>")
        for v in yticks:
            y = self.y(v)
            out.append(f'<line x1="{self.x0}" y1="{y:.1f}" x2="{self.x1}" y2="{y:.1f}" '
                       'stroke="#eee"/>')
            out.append(f'<text x="{self.x0 - 5}" y="{y + 4:.1f}" text-anchor="end">{v:g}</text>')
        return out

    def svg(self, body: list[str], label: str) -> str:
        return (f'<svg class="chart" width="{self.width}" height="{self.height}" '
                f'viewBox="0 0 {self.width} {self.height}" role="img" '
                f'aria-label="{escape(label)}">' + "".join(body) + "</svg>")


def _legend(frame: _Frame, labels: Sequence[str], x: float, y: float) -> list[str]:
    out = []
    for i, label in enumerate(labels):
        yy = y + 14 * i
        out.append(f'<line x1="{x}" y1="{yy}" x2="{x + 16}" y2="{yy}" stroke="{_color(i)}" '
                   'stroke-width="2.5"/>')
        out.append(f'<text x="{x + 20}" y="{yy + 4}">{escape(label)}</text>')
    return out


def line_chart(series: Sequence[tuple[str, Sequence[float], Sequence[float]]], *, title: str,
               xlabel: str, ylabel: str, diagonal: bool = False,
               legend_at: str = "bottom-right") -> str:
    """Curves (label, xs, ys) on [0, 1]²; one colour per series, in order."""
    f = _Frame((0.0, 1.0), (0.0, 1.0))
    ticks = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
    body = f.axes(title, xlabel, ylabel, ticks, ticks)
    if diagonal:
        body.append(f'<line x1="{f.x(0)}" y1="{f.y(0)}" x2="{f.x(1)}" y2="{f.y(1)}" '
                    'stroke="#bbb" stroke-dasharray="4 3"/>')
    for i, (label, xs, ys) in enumerate(series):
        if len(xs) == 0:
            continue
        pts = " ".join(f"{f.x(a):.1f},{f.y(b):.1f}" for a, b in zip(xs, ys, strict=True))
        body.append(f'<polyline points="{pts}" fill="none" stroke="{_color(i)}" '
                    f'stroke-width="2" data-series="{escape(label)}"/>')
    labels = [s[0] for s in series]
    if legend_at == "bottom-right":
        lx, ly = f.x1 - 130, f.y0 - 10 - 14 * (len(labels) - 1)
    else:
        lx, ly = f.x1 - 130, f.y1 + 14
    body += _legend(f, labels, lx, ly)
    return f.svg(body, title)


def strip_chart(rows: Sequence[tuple[str, Sequence[float]]], *, title: str, xlabel: str) -> str:
    """One row of dots per label (the values), with the median marked and written."""
    values = [v for _, vs in rows for v in vs]
    hi = max(1.0, float(np.ceil(max(values)))) if values else 1.0
    height = max(160, 56 * len(rows) + MARGIN["top"] + MARGIN["bottom"])
    f = _Frame((0.0, hi), (0.0, float(len(rows))), height=height)
    step = max(0.5, float(np.ceil(hi / 8 * 2) / 2))
    body = f.axes(title, xlabel, "", list(np.arange(0.0, hi + 1e-9, step)), [])
    rng = np.random.default_rng(0)  # fixed jitter: the same report renders the same
    for i, (label, vs) in enumerate(rows):
        yc = f.y(len(rows) - i - 0.5)
        body.append(f'<text x="{f.x0 + 4}" y="{yc - 14:.1f}" class="s">{escape(label)} '
                    f"(n={len(vs)})</text>")
        for v in vs:
            jitter = rng.uniform(-8, 8)
            body.append(f'<circle cx="{f.x(v):.1f}" cy="{yc + jitter:.1f}" r="3" '
                        f'fill="{_color(i)}" fill-opacity="0.55"/>')
        if len(vs):
            med = float(np.median(vs))
            body.append(f'<line x1="{f.x(med):.1f}" y1="{yc - 11:.1f}" x2="{f.x(med):.1f}" '
                        f'y2="{yc + 11:.1f}" stroke="#000" stroke-width="2"/>')
            body.append(f'<text x="{f.x(med) + 4:.1f}" y="{yc + 22:.1f}" class="s">'
                        f"median {med:.2f} s</text>")
    return f.svg(body, title)


def _nice_limits(values: Sequence[float], reference: float | None) -> tuple[float, float]:
    """Axis limits around `values` (and the reference line), padded, on a 5-unit grid."""
    points = [*values, *([] if reference is None else [reference])]
    if not points:
        return 0.0, 1.0
    lo, hi = min(points), max(points)
    pad = max((hi - lo) * 0.08, 1.0)
    return float(np.floor((lo - pad) / 5) * 5), float(np.ceil((hi + pad) / 5) * 5)


def interval_chart(rows: Sequence[tuple[str, float | None, float | None, float | None]], *,
                   title: str, xlabel: str, reference: float | None = None) -> str:
    """One row per label: its estimate as a dot and its interval (low, high) as an error bar
    with caps; a row without an interval shows the dot alone, one without an estimate only its
    label. `reference` draws a dashed vertical line (0 for differences)."""
    shown = [v for _, *vs in rows for v in vs if v is not None]
    xlim = _nice_limits(shown, reference)
    height = max(140, 26 * len(rows) + MARGIN["top"] + MARGIN["bottom"])
    room = min(LABEL_ROOM_MAX, 7 * max((len(label) for label, *_ in rows), default=0))
    f = _Frame(xlim, (0.0, float(max(len(rows), 1))), width=WIDTH + room, height=height)
    f.x0 += room - MARGIN["left"] + 8  # the labels stand left of the plotting area
    step = max(5.0, float(np.ceil((xlim[1] - xlim[0]) / 6 / 5) * 5))
    body = f.axes(title, xlabel, "", list(np.arange(xlim[0], xlim[1] + 1e-9, step)), [])
    if reference is not None:
        body.append(f'<line x1="{f.x(reference):.1f}" y1="{f.y0}" x2="{f.x(reference):.1f}" '
                    f'y2="{f.y1}" stroke="#888" stroke-dasharray="4 3"/>')
    for i, (label, mean, low, high) in enumerate(rows):
        y = f.y(len(rows) - i - 0.5)
        body.append(f'<text x="{f.x0 - 6}" y="{y + 4:.1f}" text-anchor="end">'
                    f"{escape(label)}</text>")
        if low is not None and high is not None:
            body.append(f'<line x1="{f.x(low):.1f}" y1="{y:.1f}" x2="{f.x(high):.1f}" '
                        f'y2="{y:.1f}" stroke="{_color(i)}" stroke-width="2" '
                        f'data-interval="{low:.4g},{high:.4g}"/>')
            for end in (low, high):
                body.append(f'<line x1="{f.x(end):.1f}" y1="{y - 5:.1f}" x2="{f.x(end):.1f}" '
                            f'y2="{y + 5:.1f}" stroke="{_color(i)}" stroke-width="2"/>')
        if mean is not None:
            body.append(f'<circle cx="{f.x(mean):.1f}" cy="{y:.1f}" r="4" fill="{_color(i)}" '
                        f'data-estimate="{mean:.4g}"/>')
    return f.svg(body, title)


def operating_chart(series: Sequence[tuple[str, Sequence[dict]]], *, title: str,
                    budget: float | None = None) -> str:
    """Operating curves: per series (label, points) its points joined in threshold order, x the
    false interventions per hour (log scale; 0 and anything below the first decade drawn on
    its edge, marked ≤) and y the collisions prevented in %, each with its CI as whiskers.
    A point: {"false_interventions_per_h", "false_interventions_ci", "prevented_share",
    "prevented_ci"} (shares in [0, 1]). `budget` draws a dashed vertical line."""
    xs = [p["false_interventions_per_h"] for _, pts in series for p in pts]
    xs += [v for _, pts in series for p in pts for v in p["false_interventions_ci"]]
    positive = [v for v in [*xs, budget] if v is not None and v > 0]
    lo = 10.0 ** np.floor(np.log10(min([*positive, 0.1])))
    hi = 10.0 ** np.ceil(np.log10(max([*positive, 10.0 * lo])))
    f = _Frame((float(np.log10(lo)), float(np.log10(hi))), (0.0, 100.0), height=HEIGHT + 40)
    decades = np.arange(np.log10(lo), np.log10(hi) + 1e-9)
    body = f.axes(title, "false interventions per hour of safe driving (log)",
                  "collisions prevented (%)", [], [0, 20, 40, 60, 80, 100])
    for i, d in enumerate(decades):
        x = f.x(d)
        body.append(f'<line x1="{x:.1f}" y1="{f.y0}" x2="{x:.1f}" y2="{f.y1}" stroke="#eee"/>')
        body.append(f'<text x="{x:.1f}" y="{f.y0 + 15}" text-anchor="middle">'
                    f'{"≤" if i == 0 else ""}{10.0 ** d:g}</text>')

    def gx(v: float | None) -> float:
        return f.x(float(np.log10(max(v or 0.0, lo))))

    if budget:
        body.append(f'<line x1="{gx(budget):.1f}" y1="{f.y0}" x2="{gx(budget):.1f}" '
                    f'y2="{f.y1}" stroke="#888" stroke-dasharray="4 3"/>')
    for i, (label, pts) in enumerate(series):
        shown = [p for p in pts if p["prevented_share"] is not None
                 and p["false_interventions_per_h"] is not None]
        if not shown:
            continue
        line = " ".join(f"{gx(p['false_interventions_per_h']):.1f},"
                        f"{f.y(100 * p['prevented_share']):.1f}" for p in shown)
        body.append(f'<polyline points="{line}" fill="none" stroke="{_color(i)}" '
                    f'stroke-width="1.5" data-series="{escape(label)}"/>')
        for p in shown:
            x, y = gx(p["false_interventions_per_h"]), f.y(100 * p["prevented_share"])
            (plo, phi), (flo, fhi) = p["prevented_ci"], p["false_interventions_ci"]
            if plo is not None and phi is not None:
                body.append(f'<line x1="{x:.1f}" y1="{f.y(100 * plo):.1f}" x2="{x:.1f}" '
                            f'y2="{f.y(100 * phi):.1f}" stroke="{_color(i)}" '
                            'stroke-opacity="0.5"/>')
            if flo is not None and fhi is not None:
                body.append(f'<line x1="{gx(flo):.1f}" y1="{y:.1f}" x2="{gx(fhi):.1f}" '
                            f'y2="{y:.1f}" stroke="{_color(i)}" stroke-opacity="0.5"/>')
            body.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="3" fill="{_color(i)}"/>')
    body += _legend(f, [label for label, _ in series], f.x0 + 8, f.y1 + 14)
    return f.svg(body, title)


def lead_chart(ceiling: Sequence[dict], series: Sequence[tuple[str, Sequence[dict]]], *,
               title: str) -> str:
    """Collisions prevented (%) against the warning lead (s): the oracle's curve (`ceiling`:
    {"lead_s", "prevented_share"}, drawn black and dashed, from 0 at τ = 0) and, per series
    (label, points), each threshold's point at its median lead ({"lead_s",
    "prevented_share"}; points without a lead are left out)."""
    leads = [o["lead_s"] for o in ceiling] + [p["lead_s"] for _, pts in series for p in pts
                                             if p["lead_s"] is not None]
    top = float(np.ceil(max([*leads, 1.0])))
    f = _Frame((0.0, top), (0.0, 100.0), height=HEIGHT + 40)
    body = f.axes(title, "warning lead (s): median, first true intervention to contact",
                  "collisions prevented (%)", list(np.arange(0.0, top + 1e-9, 0.5)),
                  [0, 20, 40, 60, 80, 100])
    if ceiling:
        line = " ".join(f"{f.x(t):.1f},{f.y(100 * v):.1f}" for t, v in
                        [(0.0, 0.0)] + [(o["lead_s"], o["prevented_share"] or 0.0)
                                        for o in ceiling])
        body.append(f'<polyline points="{line}" fill="none" stroke="#000" stroke-width="1.5" '
                    'stroke-dasharray="5 3" data-series="oracle"/>')
    for i, (label, pts) in enumerate(series):
        for p in pts:
            if p["lead_s"] is not None and p["prevented_share"] is not None:
                body.append(f'<circle cx="{f.x(p["lead_s"]):.1f}" '
                            f'cy="{f.y(100 * p["prevented_share"]):.1f}" r="3" '
                            f'fill="{_color(i)}" data-series="{escape(label)}"/>')
    body += _legend(f, [label for label, _ in series], f.x0 + 8, f.y1 + 14)
    body.append(f'<text x="{f.x1 - 8}" y="{f.y1 + 14}" text-anchor="end">- - oracle '
                '(engages τ s before contact)</text>')
    return f.svg(body, title)


def band_chart(series: Sequence[tuple[str, Sequence[float], Sequence[float], Sequence[float],
                                      Sequence[float]]], *,
               title: str, xlabel: str, ylabel: str) -> str:
    """Curves (label, xs, mean, low, high) with their confidence bands, x on a log2 axis
    (ticks at the xs, labelled with them), y in percentage points scaled to the values; a NaN
    point is left out of its curve and band."""
    xs_all = sorted({float(x) for _, xs, *_ in series for x in xs})
    ys_all = [v for _, _, m, lo, hi in series for v in (*m, *lo, *hi) if np.isfinite(v)]
    if not xs_all or not ys_all:
        return _Frame((0.0, 1.0), (0.0, 1.0)).svg([], title)
    ylim = _nice_limits(ys_all, None)
    logs = [float(np.log2(x)) for x in xs_all]
    f = _Frame((logs[0], logs[-1]), ylim)
    body = f.axes(title, xlabel, ylabel, logs, np.linspace(*ylim, 5).round(1).tolist(),
                  xlabels=[f"{x:g}" for x in xs_all])
    for i, (_, xs, mean, low, high) in enumerate(series):
        lx = [float(np.log2(x)) for x in xs]
        ok = [j for j in range(len(xs)) if np.isfinite(mean[j])]
        band = [j for j in ok if np.isfinite(low[j]) and np.isfinite(high[j])]
        if len(band) > 1:
            up = " ".join(f"{f.x(lx[j]):.1f},{f.y(high[j]):.1f}" for j in band)
            down = " ".join(f"{f.x(lx[j]):.1f},{f.y(low[j]):.1f}" for j in reversed(band))
            body.append(f'<polygon points="{up} {down}" fill="{_color(i)}" fill-opacity="0.12" '
                        'stroke="none"/>')
        pts = " ".join(f"{f.x(lx[j]):.1f},{f.y(mean[j]):.1f}" for j in ok)
        body.append(f'<polyline points="{pts}" fill="none" stroke="{_color(i)}" '
                    f'stroke-width="2" data-series="{escape(series[i][0])}"/>')
    body += _legend(f, [s[0] for s in series], f.x0 + 8, f.y1 + 14)
    return f.svg(body, title)


STANDALONE_CSS = ("svg{font:11px sans-serif;background:#fafafa} .t{font-size:13px;"
                  "font-weight:600} .s{font-size:11px}")


def standalone(svg: str) -> str:
    """A chart as a file of its own (an .svg an image viewer or a README shows): with the SVG
    namespace and the report's fonts, which inline charts take from the page."""
    head, rest = svg.split(">", 1)
    return (head.replace("<svg ", '<svg xmlns="http://www.w3.org/2000/svg" ', 1)
            + f"><style>{STANDALONE_CSS}</style>" + rest + "\n")
