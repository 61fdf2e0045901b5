"""End to end: bikerider serve in headless Chromium (Debian's chromium and chromedriver, driven by
selenium; nothing is downloaded).  Loads the page, edits values and measures the latency of each
edit to every figure updated, uploads the steer-by-wire experiment and waits for the diagnosis
and its plan, downloads files, and saves screenshots (``BIKERIDER_SCREENSHOTS``, default a
temporary folder).  Skipped, with the reason, only where chromium or its driver is not installed.
"""

from __future__ import annotations

import os
import shutil
import statistics
import threading
import time
from importlib import resources
from pathlib import Path

import pytest

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        not (CHROMIUM.is_file() and CHROMEDRIVER.is_file()),
        reason="Debian's chromium and chromium-driver are not installed (apt-get install chromium chromium-driver)",
    ),
]

LATENCY_GOAL_MS = 300.0
"""The issue's goal: an edit updates every figure within 300 ms at the 95th percentile."""


@pytest.fixture(scope="module")
def server():
    from bikerider.app.server import App, make_server
    from bikerider.diagnose import diagnose_files

    app = App(diagnose=lambda model, data, experiment: diagnose_files(model, data, experiment))
    httpd = make_server(app, "127.0.0.1", 0)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield app, f"http://127.0.0.1:{httpd.server_address[1]}/"
    httpd.shutdown()
    httpd.server_close()
    app.close()


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (pip install -e '.[test]')")
    from selenium.webdriver.chrome.service import Service

    downloads = tmp_path_factory.mktemp("downloads")
    profile = tmp_path_factory.mktemp("profile")
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in (
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--disable-dev-shm-usage",
        f"--user-data-dir={profile}",
        "--window-size=1400,2600",
    ):
        options.add_argument(flag)
    options.add_experimental_option(
        "prefs", {"download.default_directory": str(downloads), "download.prompt_for_download": False}
    )
    driver = webdriver.Chrome(service=Service(executable_path=str(CHROMEDRIVER)), options=options)
    driver.set_script_timeout(30)
    driver.downloads = downloads  # type: ignore[attr-defined]
    yield driver
    driver.quit()


@pytest.fixture(scope="module")
def shots(tmp_path_factory):
    folder = os.environ.get("BIKERIDER_SCREENSHOTS")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        return Path(folder)
    return tmp_path_factory.mktemp("screenshots")


def _wait(predicate, timeout: float, what: str):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")


def _latencies(driver) -> list[float]:
    return driver.execute_script("return window.bikerider.latencies.slice()")


def _edit(driver, name: str, value: str, column: int = 0) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    cell = driver.find_element(By.CSS_SELECTOR, f'input[data-name="{name}"][data-k="{column}"]')
    cell.send_keys(Keys.CONTROL, "a")  # not clear(): WebDriver's clear fires a change event of its own
    cell.send_keys(value, Keys.ENTER)


def test_the_page_in_a_browser(server, browser, shots):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    app, url = server
    browser.get(url)
    _wait(lambda: len(_latencies(browser)) >= 1, 30, "the first bicycle's figures")
    assert "Browser + Jason" in browser.find_element(By.ID, "bicycle-name").text
    paths = browser.find_elements(By.CSS_SELECTOR, "#fig-eigen path")
    assert len(paths) >= 4, "the eigenvalue figure draws the tracked modes"
    browser.save_screenshot(str(shots / "01_loaded.png"))

    # Edits: each runs each computation once, and updates every figure; the latency is measured in
    # the page from the change event to the frame after the figures were redrawn.
    trail = float(browser.find_element(By.CSS_SELECTOR, 'input[data-name="c"][data-k="0"]').get_attribute("value"))
    before = dict(app.dynamics.calls)
    n = len(_latencies(browser))
    edits = 40
    for k in range(edits):
        _edit(browser, "c", f"{trail * (1 + 0.01 * (k + 1)):.6f}")
        _wait(lambda: len(_latencies(browser)) >= n + k + 1, 10, f"edit {k + 1}")
    after = dict(app.dynamics.calls)
    for name in ("eigenvalues", "uncertainty", "side_view", "bode", "map"):
        assert after[name] - before.get(name, 0) == edits, (name, before, after)
    # The Monte Carlo sigmas of the speeds follow once the edits pause: at most once per edit.
    _wait(lambda: "Monte Carlo, 2000 draws" in browser.find_element(By.ID, "speeds").text, 20, "the Monte Carlo sigmas")
    assert 1 <= app.dynamics.calls["monte_carlo"] - before.get("monte_carlo", 0) <= edits
    latencies = _latencies(browser)[n:]
    breakdown = browser.execute_script("return window.bikerider.breakdown.slice()")[n:]
    p95 = statistics.quantiles(latencies, n=20)[-1]
    (shots / "latency.txt").write_text(
        f"{len(latencies)} edits of c, load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; "
        "latency (change -> every figure redrawn) ms: median "
        f"{statistics.median(latencies):.1f}, p95 {p95:.1f}, max {max(latencies):.1f}\n"
        + "".join(f"{t:.1f} {b}\n" for t, b in zip(latencies, breakdown))
    )
    assert p95 <= LATENCY_GOAL_MS, f"p95 latency {p95:.0f} ms over the goal of {LATENCY_GOAL_MS:g} ms: {latencies}"

    # A bad value: the error is shown next to it, as the command line words it; the page keeps working.
    mass = browser.find_element(By.CSS_SELECTOR, 'input[data-name="mB"][data-k="0"]').get_attribute("value")
    _edit(browser, "mB", "-3")
    message = _wait(
        lambda: [e.text for e in browser.find_elements(By.CSS_SELECTOR, 'tr.message[data-for="mB"] td.error')],
        10,
        "the error next to mB",
    )
    assert "mB = -3" in message[0] and "expected" in message[0]
    browser.save_screenshot(str(shots / "02_error.png"))
    _edit(browser, "mB", f"{float(mass) - 1:.6f}")
    _wait(lambda: not browser.find_elements(By.CSS_SELECTOR, 'tr.message[data-for="mB"]'), 10, "the error to go")

    # A download: the parameters as TOML, which `bikerider benchmark` reads back.
    browser.find_element(By.CSS_SELECTOR, 'button[data-kind="parameters"][data-format="toml"]').click()
    saved = _wait(lambda: list(browser.downloads.glob("BrowserJason.toml")), 20, "the downloaded TOML file")
    from bikerider.io.benchmark_file import load_benchmark_parameters

    assert load_benchmark_parameters(saved[0]).values["mB"] == pytest.approx(float(mass) - 1)
    browser.find_element(By.ID, "dl-figure-go").click()
    figure = _wait(lambda: list(browser.downloads.glob("eigenvalues.png")), 60, "the downloaded figure")
    assert figure[0].read_bytes().startswith(b"\x89PNG")
    shutil.copy(figure[0], shots / "downloaded_eigenvalues.png")

    # The closed loop under a roll-angle gain: its own figure, the open loop's unchanged.
    calls = dict(app.dynamics.calls)
    browser.find_element(By.ID, "k_phi").send_keys(Keys.CONTROL, "a")
    browser.find_element(By.ID, "k_phi").send_keys("20")
    browser.find_element(By.ID, "loop-apply").click()
    _wait(lambda: "closed loop stable" in browser.find_element(By.ID, "loop-speeds").text, 10, "the closed loop")
    assert app.dynamics.calls["closed_loop"] == calls.get("closed_loop", 0) + 1
    assert app.dynamics.calls["eigenvalues"] == calls["eigenvalues"]
    browser.execute_script("document.getElementById('fig-loop').scrollIntoView()")
    browser.save_screenshot(str(shots / "03_closed_loop.png"))

    # An uploaded bicycle (a BicycleParameters Measured file, as estimate reads it), then a bad
    # upload, which shows its error; the page goes on.
    measured = next(Path(str(resources.files("bikerider") / "data" / "bicycleparameters")).rglob("BrowserMeasured.txt"))
    browser.find_element(By.ID, "bicycle-file").send_keys(str(measured))
    browser.find_element(By.ID, "load-files").click()
    _wait(lambda: "BrowserMeasured.txt" in browser.find_element(By.ID, "bicycle-name").text, 30, "the uploaded bicycle")
    browser.find_element(By.ID, "bicycle-file").clear()
    bad = Path(browser.downloads) / "not_a_bicycle.txt"
    bad.write_text("this is no bicycle\n")
    browser.find_element(By.ID, "bicycle-file").send_keys(str(bad))
    browser.find_element(By.ID, "load-files").click()
    error = _wait(lambda: browser.find_element(By.ID, "load-error").text, 20, "the upload's error")
    assert "not_a_bicycle.txt" in error
    big = Path(browser.downloads) / "too_big.toml"
    big.write_bytes(b"# " + b"x" * (1 << 20) + b"\n")
    browser.find_element(By.ID, "bicycle-file").clear()
    browser.find_element(By.ID, "bicycle-file").send_keys(str(big))
    browser.find_element(By.ID, "load-files").click()
    _wait(lambda: "at most 1048576 bytes" in browser.find_element(By.ID, "load-error").text, 20, "the size error")
    n = len(_latencies(browser))
    _edit(browser, "c", f"{trail:.6f}")
    _wait(lambda: len(_latencies(browser)) > n, 10, "an edit after the bad upload")

    # The gap: the steer-by-wire experiment's folder, the diagnosis in the background, its report.
    sbw = Path(str(resources.files("bikerider") / "data" / "gap" / "pasma2024_sbw"))
    copy = Path(browser.downloads) / "pasma2024_sbw"
    shutil.copytree(sbw, copy)
    browser.find_element(By.ID, "gap-folder").send_keys(str(copy))
    _wait(lambda: "experiment.toml" in browser.find_element(By.ID, "gap-upload-status").text, 60, "the upload")
    browser.find_element(By.ID, "gap-run").click()
    _wait(lambda: "s)" in browser.find_element(By.ID, "gap-progress").text, 20, "the progress")
    browser.save_screenshot(str(shots / "04_gap_running.png"))
    _wait(
        lambda: browser.find_element(By.ID, "gap-summary").text or browser.find_element(By.ID, "gap-error").text,
        600,
        "the diagnosis",
    )
    assert not browser.find_element(By.ID, "gap-error").text
    summary = browser.find_element(By.ID, "gap-summary").text
    assert "steer_friction" in summary
    assert browser.find_element(By.ID, "gap-next-text").text
    images = browser.find_elements(By.CSS_SELECTOR, "#gap-figures img")
    assert images and all(browser.execute_script("return arguments[0].naturalWidth", img) > 0 for img in images)
    browser.find_element(By.ID, "gap-zip-link").click()
    _wait(lambda: list(browser.downloads.glob("gap_report.zip")), 30, "the report folder")
    browser.execute_script("document.getElementById('gap').scrollIntoView()")
    browser.save_screenshot(str(shots / "05_gap_report.png"))
