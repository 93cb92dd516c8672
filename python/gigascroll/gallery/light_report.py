"""The `light` command's report: a false-colour illuminance map of each painting (lux, with its
colour scale in lux and the painting's size in metres on the axes), the figures as JSON
(light.json) and an HTML page (index.html) that shows both. Plots are drawn by matplotlib's Agg
canvas into memory and written atomically (outputs.write_bytes)."""

from __future__ import annotations

import html
import io
import json
import math
from pathlib import Path

import numpy as np

from ..outputs import write_bytes, write_text

__all__ = ["map_png", "write_report", "report_html"]

COLORMAP = "inferno"   # perceptually uniform, dark to bright as the light itself


def map_png(lux: np.ndarray, width_m: float, height_m: float, title: str, vmax: float,
            limit_lux: float | None) -> bytes:
    """The false-colour map of one painting as PNG bytes: image x along the painting's u axis
    (metres from its left edge), image y down along v, colour 0..vmax lux (one scale for all
    the paintings of a report), thin labelled iso-lux lines (the structure within one
    painting's range), and the category's illuminance limit marked on the colour bar and
    outlined on the map (dashed, cyan)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    aspect = width_m / height_m
    fig_w = 9.0
    map_h = min(6.0, max(0.6, fig_w / aspect))
    fig = Figure(figsize=(fig_w, map_h + 1.6), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    masked = np.ma.masked_invalid(lux)
    im = ax.imshow(masked, cmap=COLORMAP, vmin=0.0, vmax=vmax, origin="upper",
                   extent=(0.0, width_m, height_m, 0.0), interpolation="nearest",
                   aspect="equal")
    ax.set_xlabel("along the painting (m)")
    ax.set_ylabel("down (m)")
    ax.set_title(title, fontsize=10)
    bar = fig.colorbar(im, ax=ax, orientation="horizontal", fraction=0.08, pad=0.02,
                       aspect=40)
    bar.set_label("illuminance (lx)")
    rows, cols = lux.shape
    xs = (np.arange(cols) + 0.5) / cols * width_m
    ys = (np.arange(rows) + 0.5) / rows * height_m
    seen = np.isfinite(lux)
    lo, hi = (float(np.nanmin(lux)), float(np.nanmax(lux))) if seen.any() else (0.0, 0.0)
    if hi > lo and min(rows, cols) >= 2:
        from matplotlib.ticker import MaxNLocator
        levels = [x for x in MaxNLocator(6).tick_values(lo, hi) if lo < x < hi]
        if levels:
            ink = "0.15" if np.nanmean(lux) > 0.6 * vmax else "white"  # legible on the map
            iso = ax.contour(xs, ys, np.ma.masked_invalid(lux), levels=levels, colors=ink,
                             linewidths=0.6, alpha=0.8)
            ax.clabel(iso, fontsize=7, fmt="%g lx")
    if limit_lux is not None and limit_lux <= vmax:
        bar.ax.axvline(limit_lux, color="cyan", linewidth=2, linestyle="--")
        if lo < limit_lux < hi and min(rows, cols) >= 2:
            ax.contour(xs, ys, np.ma.masked_invalid(lux), levels=[limit_lux], colors="cyan",
                       linewidths=1.2, linestyles="--")
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def _fmt(x, digits=0, unit="") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    return f"{x:,.{digits}f}{unit}"


def report_html(results: dict) -> str:
    """The HTML page of the report (the maps by their file names in results)."""
    e = html.escape
    cat = results["category"]
    rows, sections = [], []
    for p in results["paintings"]:
        warn = "<br>".join(e(w) for w in p["warnings"]) or "within the limits"
        rows.append(
            f"<tr><td>{e(p['name'])}</td><td>{_fmt(p['min_lux'], 1)}</td>"
            f"<td>{_fmt(p['mean_lux'], 1)}</td><td>{_fmt(p['max_lux'], 1)}</td>"
            f"<td>{_fmt(p['uniformity'], 2)}</td><td>{_fmt(p['annual_lux_hours_mean'])}</td>"
            f"<td>{_fmt(p['annual_lux_hours_max'])}</td><td>{_fmt(p['max_hours_per_year'])}</td>"
            f"<td class='{'warn' if p['warnings'] else 'ok'}'>{warn}</td></tr>")
        sections.append(f"<h3>{e(p['name'])}</h3><img src='{e(p['map'])}' alt='illuminance map "
                        f"of {e(p['name'])}'>")
    lights = "".join(
        f"<li>{e(str(light['name']))}: {e(light['colour'])}, {_fmt(light.get('lumens'))} lm"
        f"{e(light['target'])}</li>" for light in results["lights"]) or "<li>given as emitting " \
        "surfaces of the room file (no light specs)</li>"
    limit = (f"{_fmt(cat['lux'])} lx and {_fmt(cat['lux_hours'])} lx h per year"
             if cat["lux"] is not None else "no limit")
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Illuminance of the paintings: {e(results['room'])}</title>
<style>body{{font-family:sans-serif;max-width:72em;margin:1em auto;padding:0 1em}}
table{{border-collapse:collapse}}td,th{{border:1px solid #bbb;padding:0.25em 0.5em;text-align:right}}
td:first-child,td:last-child,th:last-child{{text-align:left}}.warn{{color:#a00}}.ok{{color:#060}}
img{{max-width:100%}}</style></head><body>
<h1>Illuminance of the paintings</h1>
<p>Room <b>{e(results['room'])}</b>, lighting <b>{e(results['lighting'])}</b>. Illuminance is the
irradiance on each painting's visible side at {e(results['grid_note'])}, converted to lux with
the photometric weighting of linear sRGB: lx = 683 lm/W &times; (0.2126 E<sub>R</sub> + 0.7152
E<sub>G</sub> + 0.0722 E<sub>B</sub>). The interreflected part comes from a photon map of
{_fmt(results['stats'].get('photons_stored'))} stored photons and carries its noise (patches of a
few percent at the scale of the gather radius, {_fmt(1000 * (results['stats'].get('radius') or 0))}
mm): min and max include it; more photons (<code>--photons</code>) make it smaller.</p>
<p>Category: <b>{e(cat['name'])}</b> ({limit}; {e(results['source'])}). Opening hours:
{_fmt(results['hours_per_day'], 1)} h a day, {_fmt(results['days_per_year'])} days a year
({_fmt(results['hours_per_year'])} h a year).</p>
<p>Lights:</p><ul>{lights}</ul>
<table><tr><th>painting</th><th>min lx</th><th>mean lx</th><th>max lx</th><th>uniformity
(min/mean)</th><th>lx h / year (mean)</th><th>lx h / year (max)</th><th>hours a year the limit allows</th><th>CIE 157 limits</th></tr>
{''.join(rows)}</table>
<p>The numbers: <a href="light.json">light.json</a>.</p>
<h2>Maps</h2>{''.join(sections)}
</body></html>
"""


def write_report(directory, results: dict, maps: dict[str, bytes]) -> None:
    """Writes the maps (file name -> PNG bytes), light.json and index.html into `directory`."""
    d = Path(directory)
    for name, png in maps.items():
        write_bytes(d / name, png)
    write_text(d / "light.json", json.dumps(results, indent=2, allow_nan=False) + "\n")
    write_text(d / "index.html", report_html(results))
