"""``report.html`` in a real browser: headless Chromium (the system's package)
driven by Playwright opens the report of a ``cfgplan run`` into which a
compass failure is injected, offline (every request but the file refused),
and finds the switch in the page and every picture drawn with a size."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from cfgplan.cli import commands  # noqa: F401  (loads every command module)
from cfgplan.cli.app import app
from tests.report.test_cli_report import run_trace

pytestmark = pytest.mark.slow


def test_the_report_opens_offline_and_shows_the_switch(tmp_path: Path, chromium: str) -> None:
    """The events table has the switch and its cause; the timeline and both
    diagrams are SVGs the browser lays out (a width and a height); no request
    leaves the file."""
    try:
        from playwright.sync_api import Route, sync_playwright
    except ImportError:
        pytest.fail("the report's browser test needs playwright: pip install -e '.[test]'")
    trace = run_trace(tmp_path)
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["report", str(trace), "-o", str(out)])
    assert result.exit_code == 0, result.stdout + result.stderr
    url = (out / "report.html").resolve().as_uri()
    refused: list[str] = []

    def only_the_file(route: Route) -> None:
        if route.request.url == url:
            route.continue_()
        else:
            refused.append(route.request.url)
            route.abort()

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path=chromium, args=["--no-sandbox", "--disable-gpu"]
        )
        try:
            page = browser.new_page(viewport={"width": 1300, "height": 900})
            page.route("**/*", only_the_file)
            page.goto(url, timeout=20_000)
            switch = page.wait_for_selector("#events tr.switch", timeout=10_000)
            assert switch is not None
            assert "44 → 47: compass(Emil) failed" in switch.inner_text()
            failure = page.query_selector("#events tr.failure")
            assert failure is not None and "Emil" in failure.inner_text()
            sizes = page.eval_on_selector_all(
                "section svg",
                "all => all.map(s => { const b = s.getBoundingClientRect();"
                " return [s.closest('section').id, b.width, b.height]; })",
            )
            assert [name for name, _, _ in sizes] == [
                "timeline",
                "configuration-1",
                "configuration-2",
            ]
            assert all(w > 300 and h > 150 for _, w, h in sizes), sizes
            # the timeline's text is drawn as paths: its switch line is there as a path
            paths = page.eval_on_selector_all("#timeline svg path", "all => all.length")
            assert paths > 50
            page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
        finally:
            browser.close()
    assert refused == []
