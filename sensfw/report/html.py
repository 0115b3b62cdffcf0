"""A small builder for self-contained HTML reports (figures embedded as PNG data URIs)."""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd

CSS = """
body{font-family:-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:24px auto;
max-width:1200px;color:#222;line-height:1.45}
h1{font-size:1.7em;margin-bottom:0.2em} h2{border-bottom:2px solid #ddd;padding-bottom:4px;
margin-top:1.8em} h3{margin-bottom:0.3em}
.meta{color:#666} .note{background:#fff6e0;border-left:4px solid #f0a000;padding:6px 10px;
margin:8px 0} .ok{background:#eef8ee;border-left:4px solid #3a3;padding:6px 10px;margin:8px 0}
figure{margin:12px 0} figcaption{color:#555;font-size:0.92em}
img{max-width:100%} table{border-collapse:collapse;margin:8px 0;font-size:0.9em}
th,td{border:1px solid #ccc;padding:3px 8px;text-align:right} th{background:#f2f2f2}
td:first-child,th:first-child{text-align:left} tr.sig td{background:#e8f1ff;font-weight:600}
.grid{display:grid;grid-template-columns:1fr 1fr;gap:12px}
"""


def fig_to_uri(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


class Page:
    """Accumulates sections; :meth:`write` saves one HTML file with everything inline."""

    def __init__(self, title: str, subtitle: str = ""):
        self.title, self.subtitle = title, subtitle
        self.parts: list[str] = []

    def h2(self, text: str) -> None:
        self.parts.append(f"<h2>{html.escape(text)}</h2>")

    def h3(self, text: str) -> None:
        self.parts.append(f"<h3>{html.escape(text)}</h3>")

    def p(self, text: str, cls: str | None = None) -> None:
        c = f' class="{cls}"' if cls else ""
        self.parts.append(f"<p{c}>{html.escape(text)}</p>")

    def note(self, text: str) -> None:
        self.p(text, "note")

    def figure(self, fig, caption: str = "") -> None:
        self.parts.append(f'<figure><img src="{fig_to_uri(fig)}" alt="{html.escape(caption)}">'
                          f"<figcaption>{html.escape(caption)}</figcaption></figure>")

    def table(self, frame: pd.DataFrame, highlight: pd.Series | None = None,
              floatfmt: str = "{:.4g}", index: bool = True) -> None:
        cols = ([frame.index.name or ""] if index else []) + [str(c) for c in frame.columns]
        rows = ["<tr>" + "".join(f"<th>{html.escape(c)}</th>" for c in cols) + "</tr>"]
        for i, (idx, row) in enumerate(frame.iterrows()):
            cls = ' class="sig"' if highlight is not None and bool(highlight.iloc[i]) else ""
            cells = [str(idx)] if index else []
            for v in row.to_numpy():
                cells.append(floatfmt.format(v) if isinstance(v, float) else str(v))
            rows.append(f"<tr{cls}>" + "".join(f"<td>{html.escape(c)}</td>" for c in cells)
                        + "</tr>")
        self.parts.append("<table>" + "".join(rows) + "</table>")

    def raw(self, fragment: str) -> None:
        self.parts.append(fragment)

    def write(self, path: str | Path) -> Path:
        path = Path(path)
        body = "\n".join(self.parts)
        sub = f'<p class="meta">{html.escape(self.subtitle)}</p>' if self.subtitle else ""
        path.write_text(f"<!DOCTYPE html><html><head><meta charset='utf-8'>"
                        f"<title>{html.escape(self.title)}</title><style>{CSS}</style></head>"
                        f"<body><h1>{html.escape(self.title)}</h1>{sub}{body}</body></html>")
        return path
