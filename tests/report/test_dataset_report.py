"""The dataset report: one self-contained HTML file, sections in order, images inlined as PNG,
every class in the distributions, checked in a real browser when one is installed."""

from __future__ import annotations

import base64
import shutil
import subprocess
from html.parser import HTMLParser

import pandas as pd
import pytest

from uavcas.report.dataset_report import write_report

pytestmark = pytest.mark.slow  # a module fixture takes 11 s on 2 cores: the whole file is the full suite's

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
SECTIONS = ["summary", "runs", "topology", "fidelity", "distributions", "card"]


class Page(HTMLParser):
    """Tags with their attributes, in order, and the text of each top-level section."""

    def __init__(self, text: str):
        super().__init__()
        self.tags: list[tuple[str, dict]] = []
        self.ids: list[str] = []
        self.section_text: dict[str, list[str]] = {}
        self._stack: list[str] = []  # ids of the open <section>s
        self.feed(text)
        self.close()

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append((tag, a))
        if "id" in a:
            self.ids.append(a["id"])
        if tag == "section":
            self._stack.append(a.get("id", ""))

    def handle_endtag(self, tag):
        if tag == "section":
            self._stack.pop()

    def handle_data(self, data):
        if self._stack:
            self.section_text.setdefault(self._stack[0], []).append(data)

    def text(self, section: str) -> str:
        return " ".join(self.section_text.get(section, []))


@pytest.fixture(scope="module")
def report(report_ds, tmp_path_factory):
    out = tmp_path_factory.mktemp("out")
    index = write_report(report_ds, out)
    return index, Page(index.read_text())


def test_one_file_with_every_image_an_inline_png(report):
    index, page = report
    assert sorted(p.name for p in index.parent.iterdir()) == ["index.html"]
    imgs = [a for t, a in page.tags if t == "img"]
    assert len(imgs) >= 3 + 1 + 6  # 3 attack runs' topologies, the fidelity figure, 6 feature figures
    for a in imgs:
        head, _, data = a["src"].partition(",")
        assert head == "data:image/png;base64" and base64.b64decode(data, validate=True).startswith(PNG_MAGIC)
        assert a.get("alt")
    # nothing to fetch: no script, no stylesheet link, no frame; every link is to an anchor of the page
    assert not [t for t, _ in page.tags if t in ("script", "link", "iframe", "object", "embed")]
    hrefs = [a["href"] for t, a in page.tags if t == "a" and "href" in a]
    assert hrefs and all(h.startswith("#") and h[1:] in page.ids for h in hrefs), hrefs


def test_copied_alone_it_has_no_relative_reference(report, tmp_path):
    index, _ = report
    alone = tmp_path / "elsewhere" / "report.html"
    alone.parent.mkdir()
    shutil.copy(index, alone)
    page = Page(alone.read_text())
    refs = [v for _, a in page.tags for k, v in a.items() if k in ("src", "href", "action", "poster", "data")]
    assert refs and all(v.startswith(("#", "data:image/png;base64,")) for v in refs)
    assert "url(" not in alone.read_text().split("</style>")[0]


def test_sections_in_order_summary_and_runs_first_card_collapsed(report):
    index, page = report
    sections = [a["id"] for t, a in page.tags if t == "section" and a.get("id") in SECTIONS]
    assert sections == SECTIONS
    order = [t for t, _ in page.tags]
    assert order.index("pre") > max(i for i, (t, a) in enumerate(page.tags) if t == "table")  # JSON last
    details = [a for t, a in page.tags if t == "details"]
    assert details and not [a for a in details if "open" in a]  # the card (and the long rule texts) collapsed
    summary = page.text("summary")
    assert "128 flows from 16 run(s)" in summary and "1 pass, 1 fail" in summary and "1 run(s) kept flagged" in summary


def test_run_table_names_config_seed_classes_verdict_and_links(report, report_ds):
    index, page = report
    text = page.text("runs")
    df = pd.read_parquet(report_ds / "flows.parquet", columns=["run_id", "config", "seed"]).drop_duplicates()
    for r in df.itertuples():
        assert r.run_id in text and r.config in text and str(r.seed) in text
    # the failing run is named with its scenario and the check it failed, with value and limit
    assert "replay=50,200,10,5,inc" in text and "delay_error_p99_ms 2 (limit <= 0.5)" in text
    hrefs = {a["href"] for t, a in page.tags if t == "a" and "href" in a}
    assert {"#run-run00001", "#run-run00007", "#run-run00009", "#fidelity-run00005", "#fidelity-run00000"} <= hrefs
    assert "#run-run00000" not in hrefs  # a benign run has no attack start to draw


def test_fidelity_columns_are_explained(report):
    _, page = report
    text = page.text("fidelity")
    for column in ("lost (packets)", "queue tail", "random", "transition", "unexplained",
                   "delay error p50 / p90 / p99 (ms)"):
        assert text.count(column) >= 2, column  # the table header and its explanation
    assert "queue-drop counter" in text and "random-loss rule" in text


def test_every_class_in_the_distributions_with_zeros_and_non_finite_counted(report, report_ds):
    _, page = report
    text = page.text("distributions")
    classes = set(pd.read_parquet(report_ds / "flows.parquet", columns=["label"])["label"])
    assert len(classes) == 15 and all(c in text for c in classes)
    assert "8 non-finite of 63" in text  # Benign's NaN IATs (one row in 9 of the fixture), counted not dropped


def _chromium() -> str | None:
    return next((shutil.which(b) for b in ("chromium", "chromium-headless-shell", "chromium-browser", "google-chrome")
                 if shutil.which(b)), None)


# test instrumentation appended to a copy of the page: counts the images the browser could not decode
_PROBE = ("<script>window.addEventListener('load', () => { const imgs = [...document.images];"
          " const broken = imgs.filter(i => !i.complete || i.naturalWidth === 0).length;"
          " document.body.setAttribute('data-images', imgs.length); document.body.setAttribute('data-broken', broken);"
          " if (broken) console.error('broken images: ' + broken); });</script>")


@pytest.mark.skipif(_chromium() is None, reason="no chromium binary (apt install chromium-headless-shell)")
def test_renders_in_headless_chromium_without_broken_image_or_console_message(report, tmp_path):
    index, page = report
    copy = tmp_path / "alone" / "index.html"
    copy.parent.mkdir()
    copy.write_text(index.read_text().replace("</body>", _PROBE + "</body>"))
    r = subprocess.run([_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr", "--v=0",
                        "--virtual-time-budget=10000", "--dump-dom", copy.as_uri()],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    n_img = sum(1 for t, _ in page.tags if t == "img")
    assert f'data-images="{n_img}"' in r.stdout and 'data-broken="0"' in r.stdout, r.stdout[:500]
    console = [ln for ln in r.stderr.splitlines() if ":CONSOLE" in ln]
    assert not console, console
    # the DOM as the browser built it: the summary and the run table come first, the card's JSON last
    dom = Page(r.stdout)
    h2 = [i for i, (t, _) in enumerate(dom.tags) if t == "h2"]
    tables = [i for i, (t, _) in enumerate(dom.tags) if t == "table"]
    pre = [i for i, (t, _) in enumerate(dom.tags) if t == "pre"]
    assert dom.text("summary").lstrip().startswith("Summary") and h2[0] < tables[0] < h2[1] < tables[1] < h2[2]
    assert pre == [max(i for i, (t, _) in enumerate(dom.tags) if t in ("pre", "img", "table"))]
