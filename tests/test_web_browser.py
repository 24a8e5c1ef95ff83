"""The online mode in a real browser: Playwright driving Debian's Chromium against `st run --web`.

Values update, a write and a force reach the PLC and show, a fault shows its banner and a reset
clears it, the token is required. Every view is photographed; `ST_SCREENSHOTS=docs/img` keeps
the pictures docs/web.md shows (otherwise they go to the test's temporary directory).
Skipped, with the reason, where Chromium or Playwright is missing (.ci/run installs both).
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINE = ROOT / "tests" / "data" / "web" / "line.st"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright for Python is not installed")
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium)"),
]


def _start(args: list[str], rt: bool = False) -> tuple[subprocess.Popen, str]:
    """`st run … --web 127.0.0.1:0`; (the process, the URL it printed, with the token). `rt`: with
    SCHED_FIFO, for a program that must keep its 1 ms beside a busy browser (the axes' following
    error would stop them)."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "st",
            "run",
            *args,
            "--web",
            "127.0.0.1:0",
            "--rt" if rt else "--no-rt",
            "--duration",
            "300s",
        ],
        cwd=ROOT,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
    )
    assert proc.stderr is not None
    end = time.monotonic() + 30
    while time.monotonic() < end:
        line = proc.stderr.readline()
        m = re.match(r"web: (http://\S+)", line)
        if m:
            threading.Thread(target=proc.stderr.read, daemon=True).start()  # (a full pipe would block it)
            return proc, m.group(1)
        if not line and proc.poll() is not None:
            break
    proc.kill()
    raise AssertionError("st run --web printed no URL")


def _stop(proc: subprocess.Popen) -> None:
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()


@pytest.fixture(scope="module")
def shots(tmp_path_factory) -> Path:
    where = os.environ.get("ST_SCREENSHOTS")
    out = Path(where) if where else tmp_path_factory.mktemp("screenshots")
    out.mkdir(parents=True, exist_ok=True)
    return out


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu"])
        yield b
        b.close()


@pytest.fixture(scope="module")
def line_run():
    proc, url = _start([str(LINE)])
    yield url
    _stop(proc)


def _page(browser, url: str):
    page = browser.new_page(viewport={"width": 1280, "height": 800})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto(url)
    page.get_by_test_id("state").wait_for()
    return page, errors


def _text(page, selector: str) -> str:
    return page.locator(selector).first.inner_text().strip()


def test_the_token_is_required(browser, line_run):
    base = line_run.split("/?")[0]
    page = browser.new_page()
    page.goto(base + "/")
    assert page.get_by_test_id("login-secret").is_visible()
    assert page.request.get(base + "/api/program").status == 401
    page.get_by_test_id("login-secret").fill("not-the-token")
    page.get_by_test_id("login-submit").click()
    assert page.get_by_test_id("login-error").inner_text() == "Wrong token or password."
    page.get_by_test_id("login-secret").fill(line_run.split("token=")[1])
    page.get_by_test_id("login-submit").click()
    sync_api.expect(page.get_by_test_id("state")).to_have_text("RUN", timeout=20000)
    page.close()


def test_values_update_and_the_lines_of_the_last_scan_are_marked(browser, line_run, shots):
    page, errors = _page(browser, line_run)
    page.locator('[data-testid="tree-item"][data-path="line"]').click()
    count = page.locator('.val[data-path="line.count"]').first
    sync_api.expect(count).to_have_text(re.compile(r"^\d+$"), timeout=20000)
    first = int(count.inner_text())
    sync_api.expect(count).not_to_have_text(str(first), timeout=20000)
    assert int(count.inner_text()) > first
    sync_api.expect(page.locator(".hit").first).to_be_visible(timeout=20000)
    page.screenshot(path=str(shots / "web-code.png"))
    assert errors == []
    page.close()


def test_a_write_and_a_force_reach_the_plc_and_show(browser, line_run, shots):
    page, errors = _page(browser, line_run)
    page.get_by_test_id("tab-watch").click()
    for path in ("line.count", "line.motor", "line.speed", "line.dwell"):
        page.get_by_test_id("watch-add-input").fill(path)
        page.get_by_test_id("watch-add-btn").click()
    row = page.locator('[data-testid="watch-row"][data-path="line.count"]')
    row.get_by_test_id("new-value").fill("1000000")
    row.get_by_test_id("btn-write").click()
    sync_api.expect(row.locator(".value")).to_have_text(re.compile(r"^10000\d\d$"), timeout=20000)
    motor = page.locator('[data-testid="watch-row"][data-path="line.motor"]')
    motor.get_by_test_id("new-value").fill("TRUE")
    motor.get_by_test_id("btn-force").click()
    dialog = page.get_by_test_id("confirm-dialog")
    sync_api.expect(dialog).to_be_visible()
    assert "%QX0.0" in dialog.inner_text()  # forcing an output: named, with its address
    page.get_by_test_id("confirm-yes").click()
    sync_api.expect(motor.locator(".forced")).to_have_text("FORCED", timeout=20000)
    sync_api.expect(motor.locator(".value")).to_have_text("TRUE")
    page.screenshot(path=str(shots / "web-watch.png"))
    motor.get_by_test_id("btn-unforce").click()
    sync_api.expect(motor.locator(".forced")).to_have_count(0, timeout=20000)
    sync_api.expect(motor.locator(".value")).to_have_text("FALSE", timeout=20000)  # the program's value again
    speed = page.locator('[data-testid="watch-row"][data-path="line.speed"]')
    speed.get_by_test_id("new-value").fill("fast")
    speed.get_by_test_id("btn-write").click()
    sync_api.expect(page.get_by_test_id("toast")).to_contain_text("not a literal of REAL: 'fast'", timeout=20000)
    for path in ("line.count", "line.speed"):
        page.locator(f'[data-testid="watch-row"][data-path="{path}"]').get_by_test_id("trend-check").check()
    page.get_by_test_id("tab-trends").click()
    time.sleep(1.0)  # a second of history on the chart
    page.screenshot(path=str(shots / "web-trends.png"))
    page.get_by_test_id("tab-tasks").click()
    for k in ("lat_last", "exec_last", "lat_p99"):  # every cell of the table filled, latency's last too
        sync_api.expect(page.locator(f'.task-card [data-k="{k}"]')).to_have_text(
            re.compile(r"^[\d.,]+$"), timeout=20000
        )
    time.sleep(0.5)
    page.screenshot(path=str(shots / "web-tasks.png"))
    assert errors == []
    page.close()


def test_a_fault_shows_its_banner_and_a_reset_clears_it(browser, line_run, shots):
    page, errors = _page(browser, line_run)
    page.get_by_test_id("tab-watch").click()
    page.get_by_test_id("watch-add-input").fill("line.divisor")
    page.get_by_test_id("watch-add-btn").click()
    row = page.locator('[data-testid="watch-row"][data-path="line.divisor"]')
    row.get_by_test_id("new-value").fill("0")
    row.get_by_test_id("btn-write").click()
    banner = page.get_by_test_id("fault-banner")
    sync_api.expect(banner).to_be_visible(timeout=20000)
    text = banner.inner_text()
    assert text.startswith("FAULT DIV0: division by zero") and "line.st:24, POU line, task main" in text
    sync_api.expect(page.get_by_test_id("state")).to_have_text("FAULT")
    log = page.get_by_test_id("log")  # the fault in the page's log, with where it happened
    sync_api.expect(log).to_contain_text("line.st:24: PLC fault [DIV0]: division by zero (in line, task main)")
    sync_api.expect(log).to_contain_text("state RUN → FAULT")
    page.get_by_test_id("tab-code").click()
    page.screenshot(path=str(shots / "web-fault.png"))
    page.get_by_test_id("btn-reset-warm").click()
    sync_api.expect(page.get_by_test_id("state")).to_have_text("RUN", timeout=20000)
    sync_api.expect(banner).to_be_hidden()
    assert errors == []
    page.close()


def test_motion_ethercat_and_modbus_views(browser, shots):
    with socket.socket() as s:  # a free port for the Modbus slave, to poll it as an HMI would
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    programs = ROOT / "programs"
    proc, url = _start(
        [
            str(programs / "gantry.st"),
            "--ethercat",
            str(programs / "gantry.segment.toml"),
            "--axes",
            str(programs / "gantry.axes.toml"),
            "--modbus",
            f"127.0.0.1:{port}",
        ],
        rt=True,
    )
    hmi = socket.create_connection(("127.0.0.1", port), timeout=5)
    try:
        hmi.sendall(bytes([0, 1, 0, 0, 0, 6, 1, 3, 0, 0, 0, 1]))  # read holding register 0
        hmi.recv(64)
        page, errors = _page(browser, url)
        page.get_by_test_id("tab-motion").click()
        sync_api.expect(page.get_by_test_id("view-motion")).to_contain_text("Axis 1", timeout=20000)
        time.sleep(1.5)  # the axes move: some history on the charts
        page.screenshot(path=str(shots / "web-motion.png"))
        page.get_by_test_id("tab-ethercat").click()
        sync_api.expect(page.get_by_test_id("view-ethercat")).to_contain_text("OP", timeout=20000)
        page.screenshot(path=str(shots / "web-ethercat.png"))
        page.get_by_test_id("tab-modbus").click()
        peer = f"127.0.0.1:{hmi.getsockname()[1]}"
        sync_api.expect(page.get_by_test_id("view-modbus")).to_contain_text(peer, timeout=20000)
        page.screenshot(path=str(shots / "web-modbus.png"))
        assert errors == []
        page.close()
    finally:
        hmi.close()
        _stop(proc)


# ---------------------------------------------------------------- round two (issue 35)

CELL = ROOT / "tests" / "data" / "web" / "cell.st"


@pytest.fixture(scope="module")
def cell_run():
    proc, url = _start([str(CELL)])
    yield url
    _stop(proc)


def _watch(page, *paths: str) -> None:
    page.get_by_test_id("tab-watch").click()
    for path in paths:
        page.get_by_test_id("watch-add-input").fill(path)
        page.get_by_test_id("watch-add-btn").click()


def _row(page, path: str):
    return page.locator(f'[data-testid="watch-row"][data-path="{path}"]')


def test_values_are_iec_literals_with_their_types_and_a_method_after_its_block_is_shown(browser, cell_run):
    page, errors = _page(browser, cell_run)
    _watch(page, "cell.levels[1]", "cell.levels[3]", "cell.hold", "cell.mixer.phase")
    sync_api.expect(_row(page, "cell.levels[1]").locator(".value")).to_have_text("40.0", timeout=20000)
    sync_api.expect(_row(page, "cell.levels[3]").locator(".value")).to_have_text("80.0")
    sync_api.expect(_row(page, "cell.hold").locator(".value")).to_have_text("T#1s500ms")
    sync_api.expect(_row(page, "cell.mixer.phase").locator(".value")).to_have_text(re.compile(r"^Phase#[A-Z]+$"))
    # an array element's row gets its type from the server, and a placeholder of that type
    sync_api.expect(_row(page, "cell.levels[1]").get_by_test_id("watch-type")).to_have_text("REAL")
    assert _row(page, "cell.levels[1]").get_by_test_id("new-value").get_attribute("placeholder") == "1.5"
    assert _row(page, "cell.hold").get_by_test_id("new-value").get_attribute("placeholder") == "T#1s500ms"
    # an enumeration's value is shown whole in the code view
    page.get_by_test_id("tab-code").click()
    page.locator('[data-testid="tree-item"][data-path="cell.mixer"]').click()
    badge = page.locator('.val[data-path="cell.mixer.phase"]').first
    sync_api.expect(badge).to_have_text(re.compile(r"^Phase#[A-Z]+$"), timeout=20000)
    assert badge.evaluate("(b) => b.scrollWidth <= b.clientWidth")
    sync_api.expect(page.get_by_test_id("view-code")).to_contain_text("METHOD Next : Phase")
    sync_api.expect(page.get_by_test_id("view-code")).to_contain_text("END_METHOD")
    assert errors == []
    page.close()


def test_an_unknown_watch_path_is_refused_with_the_servers_message(browser, cell_run):
    page, errors = _page(browser, cell_run)
    _watch(page, "cell.nothing")
    sync_api.expect(page.get_by_test_id("toast")).to_have_text(
        "Not watched: cell.nothing: cell has no variable 'nothing'", timeout=20000
    )
    sync_api.expect(_row(page, "cell.nothing")).to_have_count(0)
    assert errors == []
    page.close()


def test_the_forced_count_lists_them_and_unforce_all_releases_them(browser, cell_run, shots):
    page, errors = _page(browser, cell_run)
    count = page.get_by_test_id("forced-count")
    sync_api.expect(count).to_have_text("0 forced")
    _watch(page, "cell.hold", "cell.valve")
    header = [page.locator(f".watch-table th.{c}").bounding_box() for c in ("c-path", "c-value", "c-new")]
    _row(page, "cell.hold").get_by_test_id("new-value").fill("T#3s")
    _row(page, "cell.hold").get_by_test_id("btn-force").click()
    _row(page, "cell.valve").get_by_test_id("new-value").fill("TRUE")
    _row(page, "cell.valve").get_by_test_id("btn-force").click()
    page.get_by_test_id("confirm-yes").click()  # (an output: confirmed)
    sync_api.expect(count).to_have_text("2 forced", timeout=20000)
    assert "has-forced" in (count.get_attribute("class") or "")
    # forcing a row does not move the columns
    assert [page.locator(f".watch-table th.{c}").bounding_box() for c in ("c-path", "c-value", "c-new")] == header
    count.click()
    dialog = page.get_by_test_id("forced-dialog")
    sync_api.expect(dialog.get_by_test_id("forced-row")).to_have_count(2)
    sync_api.expect(dialog).to_contain_text("cell.valve")
    page.screenshot(path=str(shots / "web-forced.png"))
    page.get_by_test_id("unforce-all").click()
    confirm = page.get_by_test_id("confirm-dialog")
    sync_api.expect(confirm).to_contain_text("Release all 2 forced variables?")
    page.get_by_test_id("confirm-yes").click()
    sync_api.expect(count).to_have_text("0 forced", timeout=20000)
    sync_api.expect(page.get_by_test_id("log")).to_contain_text("unforce all")
    assert errors == []
    page.close()


def test_stop_says_the_outputs_are_at_their_safe_values_and_state_changes_are_logged(browser, cell_run, shots):
    page, errors = _page(browser, cell_run)
    sync_api.expect(page.get_by_test_id("state")).to_have_text("RUN", timeout=20000)
    banner = page.get_by_test_id("stop-banner")
    assert banner.is_hidden()
    page.get_by_test_id("btn-stop").click()
    sync_api.expect(page.get_by_test_id("state")).to_have_text("STOP", timeout=20000)
    sync_api.expect(banner).to_be_visible()
    sync_api.expect(banner).to_contain_text("physical outputs are held at their safe values")
    sync_api.expect(page.get_by_test_id("log")).to_contain_text("state RUN → STOP")
    page.screenshot(path=str(shots / "web-stop.png"))
    page.get_by_test_id("btn-start").click()
    sync_api.expect(page.get_by_test_id("state")).to_have_text("RUN", timeout=20000)
    sync_api.expect(banner).to_be_hidden()
    sync_api.expect(page.get_by_test_id("log")).to_contain_text("state STOP → RUN")
    assert errors == []
    page.close()


def test_the_layout_holds_at_800_pixels(browser, cell_run, shots):
    page = browser.new_page(viewport={"width": 800, "height": 700})
    page.goto(cell_run)
    page.get_by_test_id("state").wait_for()
    _watch(page, "cell.hold", "cell.mixer.phase")
    sync_api.expect(_row(page, "cell.hold").locator(".value")).to_have_text(re.compile(r"^T#"), timeout=20000)
    for testid in ("conn", "forced-count", "btn-reset-cold"):
        box = page.get_by_test_id(testid).bounding_box()
        assert box is not None and box["x"] + box["width"] <= 800, testid
    row = _row(page, "cell.hold")
    for testid in ("new-value", "btn-write", "btn-force", "btn-unforce", "trend-check", "btn-remove"):
        box = row.get_by_test_id(testid).bounding_box()
        assert box is not None and box["x"] + box["width"] <= 800, testid
        assert box["width"] >= (60 if testid == "new-value" else 10), testid  # there to use, not squeezed away
    assert page.get_by_test_id("view-watch").evaluate("(v) => v.scrollWidth <= v.clientWidth")
    assert page.locator("#log-title").inner_text().startswith("Log")
    page.screenshot(path=str(shots / "web-800.png"))
    page.close()


def test_a_restarted_plc_asks_the_page_to_sign_in_again(browser):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]

    def start():
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "st",
                "run",
                str(CELL),
                "--web",
                f"127.0.0.1:{port}",
                "--no-rt",
                "--duration",
                "300s",
            ],
            cwd=ROOT,
            stderr=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            text=True,
        )
        assert proc.stderr is not None
        for line in proc.stderr:
            m = re.match(r"web: (http://\S+)", line)
            if m:
                threading.Thread(target=proc.stderr.read, daemon=True).start()
                return proc, m.group(1)
        raise AssertionError("no URL")

    proc, url = start()
    page, errors = _page(browser, url)
    sync_api.expect(page.get_by_test_id("state")).to_have_text("RUN", timeout=20000)
    _stop(proc)
    sync_api.expect(page.get_by_test_id("conn")).to_have_text("disconnected", timeout=20000)
    sync_api.expect(page.get_by_test_id("state")).to_have_text("?")  # not the stale RUN
    proc, _url = start()  # the same port, a new token: the old session is unknown
    try:
        banner = page.get_by_test_id("session-banner")
        sync_api.expect(banner).to_be_visible(timeout=30000)
        sync_api.expect(banner).to_contain_text("The PLC was restarted")
        page.get_by_test_id("sign-in-again").click()
        sync_api.expect(page.get_by_test_id("login-secret")).to_be_visible(timeout=20000)
    finally:
        _stop(proc)
    page.close()


def test_trends_plot_time_in_ms_and_an_enumeration_by_its_ordinal_named_in_the_legend(browser, cell_run, shots):
    page, errors = _page(browser, cell_run)
    _watch(page, "cell.mixer.ticks", "cell.mixer.phase", "cell.hold", "cell.levels[2]")
    for path in ("cell.mixer.phase", "cell.hold", "cell.levels[2]"):
        sync_api.expect(_row(page, path).locator(".value")).not_to_have_text("…", timeout=20000)
        _row(page, path).get_by_test_id("trend-check").check()
    page.get_by_test_id("tab-trends").click()
    time.sleep(1.0)
    legend = page.locator("#trend-chart .u-legend")
    sync_api.expect(legend).to_contain_text("cell.hold (ms)")
    values = [v.strip() for v in legend.locator(".u-value").all_inner_texts()]
    assert re.fullmatch(r"\d+(\.\d+)? ms", values[2]), values  # TIME in ms
    assert values[1] in ("IDLE", "FILLING", "MIXING", "DRAINING"), values  # the member's name
    assert values[3] == "20.0", values  # a REAL as its literal
    page.screenshot(path=str(shots / "web-trends-enum.png"))
    assert errors == []
    page.close()
