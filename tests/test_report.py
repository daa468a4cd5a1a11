"""The report a lab opens (`snakemake --report`): every stage's results, looked at in a real browser.

The browser checks need a Chromium binary (Debian: ``apt-get install chromium``)
and are skipped, saying so, where none is installed.
"""

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
import yaml

from rocklab.report.html import markdown_html, table_html

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
CHROMIUM = next(filter(None, map(shutil.which, ("chromium", "chromium-browser", "google-chrome"))), None)
needs_chromium = pytest.mark.skipif(CHROMIUM is None, reason="no Chromium installed (apt-get install chromium)")

#: The report's categories, one per stage of the workflow, in its order.
STAGES = [
    "1. Quality control",
    "2. Kinematics (Sect. 2)",
    "3. Energy dissipation (Sects. 3-4)",
    "4. Model diagnosis",
    "5. Limestone blocks",
    "6. Overturning maps (Sect. 5)",
]

#: A view of the report per section: (category, subcategory, result file), None for the landing page.
VIEWS = {
    "landing": None,
    "qc_table": (STAGES[0], None, "qc.html"),
    "kinematics_figure": (STAGES[1], None, "fig09.png"),
    "series_table": (STAGES[2], "Tables", "series.html"),
    "dissipation_figure": (STAGES[2], "Figures", "fig13.png"),
    "diagnosis_text": (STAGES[3], "Summary", "diagnosis.html"),
    "diagnosis_series_figure": (STAGES[3], "Per series", "1a-2s.png"),
    "limestone_text": (STAGES[4], None, "limestone_diagnosis.html"),
    "map_figure": (STAGES[5], None, "fig21.png"),
    "map_table": (STAGES[5], None, "map_summary.html"),
}


def _chromium(url, *args, timeout=90, tries=2):
    """Run headless Chromium on url with a throwaway profile; its stdout.

    Headless Chromium with ``--virtual-time-budget`` now and then never
    exits (a known flake of the browser, independent of the page: the same
    page renders in seconds on the next try); a run that hangs is killed
    and started again, up to ``tries`` runs.  What the run produced is
    checked as before: only the hang is forgiven.
    """
    for attempt in range(1, tries + 1):
        try:
            return _chromium_once(url, *args, timeout=timeout)
        except subprocess.TimeoutExpired:
            if attempt == tries:
                raise


def _chromium_once(url, *args, timeout):
    with tempfile.TemporaryDirectory() as profile:
        run = subprocess.run(
            [
                CHROMIUM,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                f"--user-data-dir={profile}",
                # runs the report's timers (React renders, our navigation) before the capture
                "--virtual-time-budget=5000",
                *args,
                url,
            ],
            capture_output=True,
            text=True,
            timeout=timeout,
        )
    assert run.returncode == 0, run.stderr[-2000:]
    return run.stdout


def _with_script(page: str, script: str) -> str:
    # the last </body>: the report's embedded libraries hold the string too
    head, tail = page.rsplit("</body>", 1)
    return f"{head}<script>{script}</script></body>{tail}"


def _navigation(view) -> str:
    """Script that opens a category, its subcategory and a result, as clicks in the menu would.

    The report is a single-page app without addresses for its views: its
    global ``app`` (Snakemake's app.js) is driven one step per render.
    """
    category, subcategory, name = view
    return f"""
setTimeout(() => {{
  app.showCategory({json.dumps(category)});
  if ({json.dumps(subcategory)}) setTimeout(() => app.setView({{navbarMode: "subcategory",
    subcategory: {json.dumps(subcategory)}}}), 50);
  setTimeout(() => {{
    const path = Object.keys(results).find(p => p.endsWith("/" + {json.dumps(name)}));
    const kind = results[path].mime_type.startsWith("image/") ? "img" : "html";
    app.setView({{content: kind, contentPath: results[path].data_uri, resultPath: path}});
  }}, 100);
}}, 100);"""


def _report_data(report: Path, name: str):
    """A JSON variable of the report's page (results, categories)."""
    m = re.search(rf'<script id="{name}">\s*var {name} = (.*?);\s*</script>', report.read_text(), re.S)
    return json.loads(m.group(1))


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """The report of a small run: two series of two virtual tests, the limestone blocks, coarse maps of one record."""
    if not SNAKEMAKE.exists():
        pytest.skip("snakemake not installed beside this interpreter")
    from rocklab.lab.virtual_lab import VirtualTest, write_campaign

    tmp = tmp_path_factory.mktemp("report")
    one_sided = {"boundary": "one-sided", "contact_depth_mm": 120.0}
    plan = [
        VirtualTest(test_id="V0001", specimen="1a"),
        VirtualTest(test_id="V0002", specimen="1a", theta0_ratio=0.995),
        VirtualTest(test_id="V0003", specimen="2a", **one_sided),
        VirtualTest(test_id="V0004", specimen="2a", theta0_ratio=0.993, **one_sided),
    ]
    write_campaign(tmp / "campaign", plan, seed=1)
    config = {
        "raw_dir": str(tmp / "campaign"),
        "results_dir": str(tmp / "results"),
        "figures": {"fig9_specimen": "1a"},
        "statistics": {"n_boot": 200},
        "diagnosis": {"n_boot": 5},
        "maps": {"records": ["Pac164"], "n": 5, "threads": 1},
    }
    (tmp / "config.yaml").write_text(yaml.safe_dump(config))
    # a working directory of its own (Snakemake's locks and metadata): other workflow tests run at once
    common = ["campaign", "limestone", "maps", "--snakefile", str(ROOT / "Snakefile"), "--directory", str(tmp)]
    common += ["--configfile", str(tmp / "config.yaml")]
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    for extra in (["--cores", "2", "--quiet"], ["--report", str(tmp / "report.html")]):
        run = subprocess.run([str(SNAKEMAKE), *common, *extra], capture_output=True, text=True, cwd=tmp, env=env)
        assert run.returncode == 0, run.stderr[-3000:]
    return tmp / "report.html", tmp / "results"


def test_report_holds_every_stage_with_captions(report):
    path, results = report
    categories = _report_data(path, "categories")
    assert sorted(categories) == STAGES
    assert set(categories[STAGES[2]]) == {"Tables", "Figures"}
    assert set(categories[STAGES[3]]) == {"Summary", "Per series"}
    items = _report_data(path, "results")
    names = {Path(p).name: entry for p, entry in items.items()}
    pages = ["qc", "kinematics", "tests", "series", "table3", "summary", "amplitude_laws", "effects"]
    pages += ["diagnosis", "campaign_effects", "limestone_diagnosis", "map_summary", "map_reductions", "map_comparison"]
    assert {f"{p}.html" for p in pages} <= set(names)
    assert {n for n in names if n.endswith(".csv")} == set(), "tables are shown as pages, not offered as downloads"
    figures = {f"fig{n:02d}.png" for n in (6, 8, 9, 10, 11, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23)}
    assert figures <= set(names)
    # every series the diagnosis names has its figure, labelled by its series
    series = {e["key"] for e in json.loads((results / "diagnosis.json").read_text()) if e["scope"] == "series"}
    assert series == {"1a-2s", "2a-1s-cd120"}
    per_series = {e["labels"]["series"] for e in items.values() if e["labels"] and "series" in e["labels"]}
    assert per_series == series
    for name, entry in names.items():
        assert entry["caption"].strip(), f"{name} has no caption"
        assert entry["labels"], f"{name} is listed by its path, not by what it is"
    assert "Series 1a-2s" in names["1a-2s.png"]["caption"]
    assert names["qc.html"]["mime_type"] == "text/html"


@needs_chromium
def test_every_section_renders_in_a_browser(report, tmp_path):
    """A screenshot per section: each shows something, and something else than the others."""
    path, _ = report
    page = path.read_text()
    shots = {}
    for name, view in VIEWS.items():
        html = tmp_path / f"{name}.html"
        html.write_text(page if view is None else _with_script(page, _navigation(view)))
        png = tmp_path / f"{name}.png"
        _chromium(html.as_uri(), f"--screenshot={png}", "--window-size=1400,2000")
        shots[name] = matplotlib.image.imread(png)[..., :3]
    for name, img in shots.items():
        content = img[:, 500:]  # right of the menu: the figure, table or text of the view
        colours = np.unique((content.reshape(-1, 3) * 255).astype(np.uint8), axis=0)
        assert len(colours) > 20, f"{name}: blank ({len(colours)} colours)"
    digests = {name: img.tobytes() for name, img in shots.items()}
    assert len(set(digests.values())) == len(digests), "two sections show the same screen"
    print(f"screenshots: {tmp_path}")


@needs_chromium
def test_table_page_filters_and_sorts_in_a_browser(tmp_path):
    """The filter boxes and a header click, run by the browser on a table page."""
    csv = "test_id,valid,residual_top_mm\nT3,True,0.2\nT1,False,3.1\nT2,True,1.7\nT10,True,\n"
    page = table_html(csv, "qc.csv")
    script = """
const boxes = document.querySelectorAll("thead input");
boxes[2].value = ">1"; boxes[2].dispatchEvent(new Event("input"));
document.querySelectorAll("th.sort")[0].click();
document.body.dataset.filtered = document.getElementById("shown").textContent;
document.body.dataset.order = Array.from(document.querySelectorAll("tbody tr"), r => r.cells[0].textContent).join(" ");
boxes[2].value = ""; boxes[2].dispatchEvent(new Event("input"));
document.getElementById("filter-all").value = "true t1";
document.getElementById("filter-all").dispatchEvent(new Event("input"));
document.body.dataset.words = document.getElementById("shown").textContent;
"""
    html = tmp_path / "qc.html"
    html.write_text(_with_script(page, script))
    dom = _chromium(html.as_uri(), "--dump-dom")
    body = re.search(r"<body([^>]*)>", dom).group(1)
    assert 'data-filtered="2"' in body  # 3.1 and 1.7; the empty cell is no number
    assert 'data-order="T1 T2 T3 T10"' in body  # natural order of the ids
    assert 'data-words="1"' in body  # T10: valid, and "t1" in its id


def test_table_page_shows_cells_as_written_and_describes_columns():
    csv = "test_id,valid,reject_detail,x\nT1,False,top <3 mm> & more,0.123456789\nT2,True,,1e-05\n"
    schema = {"description": "Every test.", "properties": {"valid": {"description": "Passes every rule."}}}
    page = table_html(csv, "qc.csv", schema)
    assert "<td>top &lt;3 mm&gt; &amp; more</td>" in page
    assert ">0.123456789</td>" in page and ">1e-05</td>" in page
    assert page.count('<tr class="rejected">') == 1
    assert 'title="Passes every rule."' in page and "<dd>Passes every rule.</dd>" in page
    assert '<p class="lead">Every test.</p>' in page
    assert 'download="qc.csv" href="data:text/csv;base64,' in page


def test_markdown_page_renders_what_the_reports_write():
    text = (
        "# Model diagnosis\n\nMethod: `rocklab.diagnosis`, a *note*.\n\n## series 1a-2s (two-sided, 2 tests)\n\n"
        "**Verdict: none** — x < 1\n\n| effect | 95% CI |\n|---|---|\n| scale | [0.9, 1.0] |\n\n"
        "- first item\n- second **item**\n"
    )
    # markdown-it puts a line break between block tags: the assertions read the page without them
    page = re.sub(r">\n<", "><", markdown_html(text, "diagnosis.md"))
    assert "<title>Model diagnosis</title>" in page
    assert "<h1>Model diagnosis</h1>" in page and "<h2>series 1a-2s (two-sided, 2 tests)</h2>" in page
    assert "<p>Method: <code>rocklab.diagnosis</code>, a <em>note</em>.</p>" in page
    assert "<p><strong>Verdict: none</strong> — x &lt; 1</p>" in page
    assert "<thead><tr><th>effect</th><th>95% CI</th></tr></thead>" in page
    assert "<tbody><tr><td>scale</td><td>[0.9, 1.0]</td></tr></tbody>" in page
    assert "<ul><li>first item</li><li>second <strong>item</strong></li></ul>" in page


@pytest.mark.parametrize("schema", sorted((ROOT / "workflow" / "schemas").glob("*.schema.yaml")), ids=lambda p: p.name)
def test_every_column_description_is_read_whole(schema):
    """A comma in an unquoted flow-mapping description cuts it (its tail becomes stray keys)."""
    for column, spec in yaml.safe_load(schema.read_text()).get("properties", {}).items():
        stray = [k for k, v in spec.items() if v is None]
        assert not stray, f"{column}: description cut at {stray}"
