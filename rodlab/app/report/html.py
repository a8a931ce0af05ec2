"""The look of every rodlab HTML page: one stylesheet, figures embedded as data URIs, labelled tables.

Pages are self-contained (no scripts, no links out), so a report can be mailed or archived as one file.
"""
from __future__ import annotations

import base64
import html
import math
import struct
from pathlib import Path

from rodlab.core.figures_bg import wait_for_figure

__all__ = ["CSS", "esc", "img_tag", "figure", "table", "matrix_table", "fmt", "page"]

CSS = """body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222}h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
h3{margin-bottom:.3em}table{border-collapse:collapse;margin:.6em 0}td,th{border:1px solid #ccc;padding:.25em .6em;
text-align:right}th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}img{max-width:100%;
border:1px solid #eee;margin:.4em 0}.grid{display:grid;grid-template-columns:1fr 1fr;gap:.6em}
.views{display:flex;flex-wrap:wrap;gap:.6em;align-items:flex-start}.views figure{margin:0}
figure{margin:.6em 0}figcaption{color:#555;font-size:.9em}.note{color:#555;font-size:.92em}
.bad{color:#b00020;font-weight:bold}.good{color:#1b6e20;font-weight:bold}
code{background:#f4f4f4;padding:0 .2em}td.l,th.l{text-align:left}"""


def esc(v) -> str:
    return html.escape(str(v))


def fmt(v, spec: str = ".3g") -> str:
    """A number for a table cell; ``—`` for None / NaN / not a number."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    try:
        return format(v, spec)
    except (TypeError, ValueError):
        return esc(v)


def _png_size(data: bytes) -> tuple[int, int] | None:
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        return None
    return struct.unpack(">II", data[16:24])


def img_tag(base: Path, rel, alt: str, scale: float | None = None) -> str:
    """An ``<img>`` with the PNG ``base/rel`` embedded as a data URI (a note if it is missing).

    ``scale``: show the image at this fraction of its pixel size (figures side by side at one scale)."""
    if not rel:
        return ""
    p = Path(base) / rel
    wait_for_figure(p)                          # rendered in the background (rodlab demo): written first
    if not p.exists():
        return f"<p class='note'>missing figure {esc(rel)}</p>"
    raw = p.read_bytes()
    style = ""
    size = _png_size(raw) if scale else None
    if size:
        style = f" style='width:{size[0] * scale:.0f}px'"
    data = base64.b64encode(raw).decode("ascii")
    return f"<img alt='{esc(alt)}'{style} src='data:image/png;base64,{data}'>"


def figure(path: Path, caption: str, scale: float | None = None) -> str:
    """A figure with its caption; the caption names the file, so the PNG can be found beside the report."""
    return (f"<figure>{img_tag(path.parent, path.name, caption, scale)}<figcaption>{esc(caption)} "
            f"(<code>{esc(path.name)}</code>)</figcaption></figure>")


def table(header: list[str], rows: list[list], left: int = 1) -> str:
    """A table: ``header`` strings, ``rows`` of cells already formatted (escaped here); the first ``left``
    columns are left-aligned."""
    head = "".join(f"<th{' class=l' if i < left else ''}>{esc(h)}</th>" for i, h in enumerate(header))
    body = "".join("<tr>" + "".join(f"<td{' class=l' if i < left else ''}>{esc(c)}</td>" for i, c in enumerate(r))
                   + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def matrix_table(m, unit: str, cause: str, scale: float = 1e3) -> str:
    """A 3 x 3 compliance matrix with its rows (ball displacement along x_T, y_T, z_T) and columns (``cause``
    along x_T, y_T, z_T) named, in ``unit`` (values times ``scale``)."""
    head = (f"<tr><th>[{esc(unit)}]</th>" + "".join(f"<th>{esc(cause)} along {a}_T</th>" for a in "xyz") + "</tr>")
    rows = "".join(f"<tr><th>ball moves along {a}_T</th>"
                   + "".join(f"<td>{round(v * scale, 3) + 0.0:+.3f}</td>" for v in row) + "</tr>"
                   for a, row in zip("xyz", m))
    return f"<table>{head}{rows}</table>"


def page(title: str, body: list[str], intro: str = "") -> str:
    """The whole self-contained page."""
    return "\n".join([f"<!doctype html><html lang=en><head><meta charset=utf-8><title>{esc(title)}</title>"
                      f"<style>{CSS}</style></head><body>", f"<h1>{esc(title)}</h1>", intro, *body,
                      "</body></html>"])
