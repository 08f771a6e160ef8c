"""The operator console in a real (headless) Chromium: the page, the 3-D canvas, the GUI."""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("viser")

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGUMENTS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--enable-unsafe-swiftshader",  # software WebGL for the 3-D canvas
    "--use-angle=swiftshader",
]


def test_page_shows_the_robot_and_the_controls(tmp_path: Path) -> None:
    if not CHROMIUM.exists():
        pytest.skip("no /usr/bin/chromium (Debian: apt-get install chromium)")
    playwright = pytest.importorskip(
        "playwright.sync_api", reason="playwright drives the headless browser"
    )
    from pneumaquad.console.app import ConsoleApp

    app = ConsoleApp(configuration="quadruped", environment="block", port=0, real_time=False)
    try:
        app.advance(600)  # standing on its feet, contacts loaded
        app.teleop.set_stylus("front_right", np.array([0.0, 0.05, 0.05]))
        app.teleop.set_stylus("front_left", np.array([0.5, 0.0, 0.0]))  # clamped: red
        app.advance(400)
        with playwright.sync_playwright() as driver:
            browser = driver.chromium.launch(
                executable_path=str(CHROMIUM), headless=True, args=CHROMIUM_ARGUMENTS,
                chromium_sandbox=False,
            )
            try:
                page = browser.new_page(viewport={"width": 1400, "height": 900})
                page.goto(f"http://127.0.0.1:{app.port}/", timeout=30_000)
                page.wait_for_selector("canvas", timeout=30_000)
                for label in ("Start", "Pause", "Reset", "Configuration", "Supply [kPa g]",
                              "Walking mode", "Stop walking"):
                    page.get_by_text(label, exact=True).first.wait_for(timeout=30_000)
                page.get_by_text("clamped", exact=True).first.wait_for(timeout=30_000)
                # a control clicked in the browser changes the simulation
                before = app.simulation.time
                page.get_by_text("Step 20 ms", exact=True).first.click()
                deadline = time.monotonic() + 20.0
                while app.simulation.time <= before and time.monotonic() < deadline:
                    page.wait_for_timeout(100)
                stepped = app.simulation.time - before
                page.wait_for_timeout(3000)  # let the software renderer draw the scene
                screenshot = tmp_path / "console.png"
                page.screenshot(path=str(screenshot))
            finally:
                browser.close()
    finally:
        app.close()
    assert stepped == pytest.approx(app.chunk_steps * app.simulation.control_step)
    assert screenshot.stat().st_size > 20_000
    keep = os.environ.get("PNEUMAQUAD_SCREENSHOT")
    if keep:  # e.g. docs/images/console.png
        shutil.copyfile(screenshot, keep)
    print(f"screenshot: {screenshot}")
