"""Pages of the Snakemake report: result tables and markdown reports as self-contained HTML.

``snakemake --report`` shows an HTML result in its browser view but offers a
CSV or markdown file as a download only; these pages make the QC table, the
per-series tables and the diagnoses readable in the report itself.  A table
page sorts by any column (click its header), filters rows (one box over every
column, one per column, numeric comparisons such as ``>0.9``), describes each
column from its JSON schema (``workflow/schemas``) and carries the CSV as a
download.  No file outside the page is read: the report is opened offline.
"""

from __future__ import annotations

import base64
import csv
import html
from collections.abc import Mapping
from io import StringIO
from pathlib import Path
from typing import Any

from markdown_it import MarkdownIt

from rocklab.io import load_schema

_STYLE = """
body { font: 14px/1.45 system-ui, sans-serif; margin: 1em 1.5em; color: #1e293b; }
h1 { font-size: 1.35em; margin: 0.2em 0 0.4em; }
h2 { font-size: 1.15em; margin: 1.4em 0 0.4em; border-bottom: 1px solid #cbd5e1; }
p.lead { color: #475569; margin: 0 0 0.8em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 13px; }
th, td { border: 1px solid #cbd5e1; padding: 2px 6px; text-align: left; vertical-align: top; }
thead th { background: #e2e8f0; position: sticky; top: 0; }
thead tr.filters th { top: 1.8em; background: #f1f5f9; }
th.sort { cursor: pointer; white-space: nowrap; }
th.sort[aria-sort=ascending]::after { content: " \\25B2"; }
th.sort[aria-sort=descending]::after { content: " \\25BC"; }
tbody tr:nth-child(even) { background: #f8fafc; }
tbody tr.rejected { background: #fee2e2; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
input { font: inherit; padding: 2px 4px; }
thead input { width: 100%; box-sizing: border-box; min-width: 4em; }
.bar { display: flex; gap: 1.5em; align-items: center; margin: 0.4em 0; }
dl.columns { display: grid; grid-template-columns: max-content auto; gap: 2px 1em; font-size: 13px; }
dl.columns dt { font-family: monospace; }
dl.columns dd { margin: 0; color: #475569; }
code { background: #f1f5f9; padding: 0 3px; }
"""

# Sorts by a header click and keeps the rows that pass every filter: the box
# over all columns (every word somewhere in the row) and the per-column boxes
# (a substring, or a comparison such as >0.9, <=3, =T0001).
_SCRIPT = """(() => {
const table = document.querySelector("table.data");
const rows = Array.from(table.tBodies[0].rows);
const all = document.getElementById("filter-all");
const boxes = Array.from(table.querySelectorAll("thead input"));
const shown = document.getElementById("shown");
const number = s => (s.trim() === "" ? NaN : Number(s));
function passes(cell, query) {
  const m = query.match(/^(<=|>=|<|>|=)\\s*(.+)$/);
  if (!m) return cell.toLowerCase().includes(query.toLowerCase());
  const [x, y] = [number(cell), number(m[2])];
  if (Number.isNaN(x) || Number.isNaN(y)) return m[1] === "=" && cell === m[2];
  return {"<": x < y, "<=": x <= y, ">": x > y, ">=": x >= y, "=": x === y}[m[1]];
}
function refresh() {
  const words = all.value.toLowerCase().split(/\\s+/).filter(Boolean);
  let n = 0;
  for (const row of rows) {
    const cells = Array.from(row.cells, c => c.textContent);
    const text = cells.join(" ").toLowerCase();
    const ok = words.every(w => text.includes(w)) &&
      boxes.every((b, i) => !b.value.trim() || passes(cells[i], b.value.trim()));
    row.hidden = !ok;
    n += ok;
  }
  shown.textContent = n;
}
all.addEventListener("input", refresh);
boxes.forEach(b => b.addEventListener("input", refresh));
table.querySelectorAll("th.sort").forEach((th, i) => th.addEventListener("click", () => {
  const up = th.getAttribute("aria-sort") !== "ascending";
  table.querySelectorAll("th.sort").forEach(h => h.removeAttribute("aria-sort"));
  th.setAttribute("aria-sort", up ? "ascending" : "descending");
  const key = r => r.cells[i].textContent;
  rows.sort((a, b) => {
    const [x, y] = [number(key(a)), number(key(b))];
    const c = !Number.isNaN(x) && !Number.isNaN(y) ? x - y : key(a).localeCompare(key(b), undefined, {numeric: true});
    return up ? c : -c;
  });
  rows.forEach(r => table.tBodies[0].appendChild(r));
}));
})();
"""


def _page(title: str, body: str, script: str = "") -> str:
    script = f"<script>{script}</script>" if script else ""
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head>"
        f"<body>{body}{script}</body></html>\n"
    )


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return text.strip() != ""


def table_html(csv_text: str, name: str, schema: Mapping[str, Any] | None = None) -> str:
    """A sortable, filterable HTML page of a CSV table.

    Parameters
    ----------
    csv_text : str
        The table as written by the workflow; cells are shown as written
        (no rounding), an empty cell stays empty.
    name : str
        File name of the table (the page's title and the download's name).
    schema : dict, optional
        Its JSON schema: the description becomes the lead paragraph and each
        column's description its header tooltip and an entry of the column list.

    Returns
    -------
    str
        The HTML document.  Rows whose ``valid`` column reads False (the QC
        table) are shaded.
    """
    # the cells as written: the csv module, not pandas (the page jobs start
    # faster without it); a blank line is no row
    columns, *rows = [row for row in csv.reader(StringIO(csv_text)) if row] or [[]]
    schema = schema or {}
    described = {k: v.get("description", "") for k, v in schema.get("properties", {}).items()}
    esc = html.escape
    head = "".join(f'<th class="sort" title="{esc(described.get(c, ""))}">{esc(c)}</th>' for c in columns)
    filters = "".join(f'<th><input aria-label="filter {esc(c)}" placeholder="filter"></th>' for c in columns)
    body = []
    valid = columns.index("valid") if "valid" in columns else None
    for row in rows:
        shade = ' class="rejected"' if valid is not None and row[valid] == "False" else ""
        cells = "".join(f"<td{' class=num' if _is_number(v) else ''}>{esc(v)}</td>" for v in row)
        body.append(f"<tr{shade}>{cells}</tr>")
    listed = "".join(f"<dt>{esc(c)}</dt><dd>{esc(described[c])}</dd>" for c in columns if described.get(c))
    download = base64.b64encode(csv_text.encode()).decode()
    lead = f'<p class="lead">{esc(schema["description"])}</p>' if schema.get("description") else ""
    page = (
        f"<h1>{esc(name)}</h1>{lead}"
        '<div class="bar"><label>Filter rows <input id="filter-all" size="30" '
        'placeholder="words anywhere in the row"></label>'
        f'<span><span id="shown">{len(rows)}</span> of {len(rows)} rows</span>'
        f'<a download="{esc(name)}" href="data:text/csv;base64,{download}">download {esc(name)}</a></div>'
        f'<table class="data"><thead><tr>{head}</tr><tr class="filters">{filters}</tr></thead>'
        f"<tbody>{''.join(body)}</tbody></table>"
        + (f'<h2>Columns</h2><dl class="columns">{listed}</dl>' if listed else "")
    )
    return _page(name, page, _SCRIPT)


def markdown_html(text: str, name: str) -> str:
    """An HTML page of a markdown report of the workflow (``diagnosis.md``...).

    Parameters
    ----------
    text : str
        Markdown (CommonMark with pipe tables, rendered by markdown-it-py).
    name : str
        File name of the report (the page's title when it has no ``#`` heading).

    Returns
    -------
    str
        The HTML document.
    """
    md = MarkdownIt("commonmark").enable("table")
    tokens = md.parse(text)
    heading = next((k for k, t in enumerate(tokens) if t.type == "heading_open" and t.tag == "h1"), None)
    title = tokens[heading + 1].content if heading is not None else name
    return _page(title, md.renderer.render(tokens, md.options, {}))


def report_page(source: str | Path, schema: str | Path | None = None, name: str | None = None) -> str:
    """The HTML page of a result file for the report: a table (``.csv``) or a text (``.md``).

    Parameters
    ----------
    source : str or pathlib.Path
        The result file.
    schema : str or pathlib.Path, optional
        JSON schema of a table (``workflow/schemas``), for its column descriptions.
    name : str, optional
        The file's name on the page (e.g. ``maps/summary.csv``); default its file name.
    """
    source = Path(source)
    text, name = source.read_text(), name or source.name
    if source.suffix == ".md":
        return markdown_html(text, name)
    return table_html(text, name, load_schema(schema) if schema else None)
