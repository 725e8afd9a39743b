"""A viewer page opened in headless Chromium (Playwright), for screenshots and tests.

WebGL on ANGLE/SwiftShader (no GPU); needs Debian's ``chromium`` and the ``playwright`` package.
"""

from __future__ import annotations

import importlib.util
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from dice_env.disk import write_atomically

# Headless, software WebGL, and no background connections (refused on a closed network).
CHROMIUM_ARGS = ("--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
                 "--enable-unsafe-swiftshader", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run",
                 "--disable-quic")
READY = "window.diceViewer && window.diceViewer.ready"  # the page's first picture is drawn


def chromium() -> str | None:
    """The installed Chromium's path, or None."""
    return shutil.which("chromium") or shutil.which("chromium-browser")


def missing() -> str | None:
    """What is missing to open a page (Chromium or Playwright), or None."""
    if chromium() is None:
        return "no Chromium found (Debian: apt-get install chromium)"
    if importlib.util.find_spec("playwright") is None:
        return "no playwright (pip install playwright)"
    return None


@contextmanager
def opened(page: str | Path, size: tuple[int, int] = (1000, 700),
           errors: list[str] | None = None) -> Iterator[Any]:
    """``page`` open and drawn in headless Chromium: yields Playwright's page object.

    ``size``: the viewport (width, height) in CSS pixels; ``errors`` collects console errors and
    uncaught exceptions. ``RuntimeError`` where Chromium or Playwright is missing.
    """
    reason = missing()
    if reason is not None:
        raise RuntimeError(reason)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium(),
                                             args=list(CHROMIUM_ARGS), timeout=20_000)
        try:
            tab = browser.new_page(viewport={"width": size[0], "height": size[1]})
            if errors is not None:
                tab.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
                tab.on("pageerror", lambda e: errors.append(str(e)))
            tab.goto(Path(page).resolve().as_uri())
            tab.wait_for_function(READY, timeout=15_000)
            yield tab
        finally:
            browser.close()


def screenshot(page: str | Path, path: str | Path, *, t: float | None = None,
               size: tuple[int, int] = (1000, 700)) -> Path:
    """A PNG of ``page`` at simulated time ``t`` (s; None: the end of the first throw)."""
    with opened(page, size) as tab:
        tab.evaluate("t => window.diceViewer.setTime(t)", 1e9 if t is None else float(t))
        write_atomically(Path(path), tab.screenshot())
    return Path(path)
