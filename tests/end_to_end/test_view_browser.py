"""The live view (`run --view`) in a real browser: Debian's Chromium, headless, driven through
chromium-driver by Selenium. The page shows the golden frame on its canvas after one step from a
paused start, the console's text arrives, the run goes on with the page closed and ends with
Ctrl-C as always; a press of the page's BOOT key reaches the firmware (tests/firmware/boot_key.c
tells it on the console and lights the green LED while the key is down).

tools/ensure-toolchain.sh installs chromium and chromium-driver with apt-get; where that could
not be done the tests are skipped, saying so (make test lists skips with their reasons)."""
from __future__ import annotations

import base64
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from PIL import Image

from suite import ROOT

CHROMIUM = shutil.which("chromium")
CHROMEDRIVER = shutil.which("chromedriver")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None or CHROMEDRIVER is None,
    reason="the live view's browser test needs Debian's chromium and chromium-driver, which "
           "tools/ensure-toolchain.sh installs with apt-get: that install failed or was not run")

DEFAULT_GOLDEN = ROOT / "tests" / "golden" / "default"
WAIT_S = 60

CANVAS_RGB = """
const canvas = document.getElementById("lcd");
const rgba = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
let bytes = "";
for (let i = 0; i < rgba.length; i += 4) bytes += String.fromCharCode(rgba[i], rgba[i + 1], rgba[i + 2]);
return [canvas.width, canvas.height, btoa(bytes)];
"""


@pytest.fixture(scope="module")
def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    os.environ["SE_OFFLINE"] = "true"          # the driver is Debian's: Selenium Manager fetches nothing
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                     "--window-size=1300,1000", "--no-first-run", "--disable-extensions"):
        options.add_argument(argument)
    driver = webdriver.Chrome(options=options, service=Service(CHROMEDRIVER))
    driver.set_script_timeout(WAIT_S)
    yield driver
    driver.quit()


def start_view(*args: str) -> tuple[subprocess.Popen, str]:
    """The board model serving its live view on a free port; returns the process and the page's URL."""
    process = subprocess.Popen([sys.executable, "-m", "emulator", "run", *args, "--view", "0", "--quiet"],
                               cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = process.stderr.readline()
    match = re.search(r"the live view is at (http://127\.0\.0\.1:\d+/)", line)
    assert match, line + process.stderr.read()
    return process, match.group(1)


def stop(process: subprocess.Popen, signalled: bool = False) -> tuple[int, str]:
    """Ctrl-C (unless `signalled`: sent already), and the process's status and standard error."""
    if process.poll() is None and not signalled:
        process.send_signal(signal.SIGINT)
    try:
        _, errors = process.communicate(timeout=WAIT_S)
    finally:
        if process.poll() is None:
            process.kill()
    return process.returncode, errors


def wait_until(browser, check, what: str):
    from selenium.webdriver.support.ui import WebDriverWait
    return WebDriverWait(browser, WAIT_S, poll_frequency=0.05).until(lambda driver: check(driver), what)


def text_of(browser, element_id: str) -> str:
    return browser.execute_script(f"return document.getElementById({element_id!r}).textContent")


def test_the_page_shows_the_golden_frame_and_the_console(browser, firmware, card, tmp_path):
    from selenium.webdriver.common.by import By
    out = tmp_path / "out"
    process, url = start_view(str(firmware), "--sd", str(card), "--out", str(out), "--view-paused")
    signalled = False
    try:
        browser.get(url)
        wait_until(browser, lambda b: text_of(b, "state").startswith("paused"), "the page says paused")
        assert browser.find_element(By.ID, "lcd").get_attribute("data-seq") == "0"     # nothing drawn yet
        browser.find_element(By.ID, "step").click()
        wait_until(browser, lambda b: b.find_element(By.ID, "lcd").get_attribute("data-seq") == "1"
                   and text_of(b, "state").startswith("paused"), "one step's frame")
        assert browser.find_element(By.ID, "lcd").get_attribute("data-index") == "0"
        width, height, pixels = browser.execute_script(CANVAS_RGB)
        shown = np.frombuffer(base64.b64decode(pixels), dtype=np.uint8).reshape(height, width, 3)
        golden = np.asarray(Image.open(DEFAULT_GOLDEN / "frame_0000.png").convert("RGB"))
        assert np.array_equal(shown, golden), f"{np.count_nonzero((shown != golden).any(axis=2))} pixels differ"
        console = text_of(browser, "console")
        assert "boot: hart 0 up" in console and "lcd: ST7789V ready" in console
        browser.find_element(By.ID, "continue").click()
        wait_until(browser, lambda b: "frame 3\n" in text_of(b, "console"), "the console's 'frame 3'")
        browser.get("about:blank")                 # the page is closed: the run goes on
        frames = len(list(out.glob("frame_*.png")))
        deadline = time.monotonic() + WAIT_S
        while len(list(out.glob("frame_*.png"))) <= frames + 2:
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        browser.get(url)                           # and ends with Ctrl-C, which the page is told
        wait_until(browser, lambda b: text_of(b, "state").startswith("running"), "the page says running")
        process.send_signal(signal.SIGINT)
        signalled = True
        wait_until(browser, lambda b: "interrupted" in text_of(b, "banner"), "the page says the run ended")
    finally:
        status, errors = stop(process, signalled)
    assert status == 130 and "Traceback" not in errors, errors
    assert json.loads((out / "run.json").read_text())["exit"] == "interrupted"


def test_the_boot_key_pressed_on_the_page_reaches_the_firmware(browser, c_firmware, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    out = tmp_path / "out"
    process, url = start_view(str(c_firmware / "boot_key.elf"), "--out", str(out))
    try:
        browser.get(url)
        wait_until(browser, lambda b: "press the BOOT key" in text_of(b, "console"), "the firmware's prompt")
        green = browser.find_element(By.CSS_SELECTOR, ".led.green")
        assert "lit" not in green.get_attribute("class")
        boot = browser.find_element(By.ID, "boot")
        ActionChains(browser).click_and_hold(boot).perform()
        wait_until(browser, lambda b: "BOOT key pressed (1)" in text_of(b, "console"), "the press on the console")
        wait_until(browser, lambda b: "lit" in green.get_attribute("class"), "the green LED lit")
        ActionChains(browser).release(boot).perform()
        wait_until(browser, lambda b: "BOOT key released (1)" in text_of(b, "console"), "the release")
        wait_until(browser, lambda b: "lit" not in green.get_attribute("class"), "the green LED dark")
        boot.click()                               # a click: down and up at once, still seen
        wait_until(browser, lambda b: "BOOT key released (2)" in text_of(b, "console"), "the click")
    finally:
        status, errors = stop(process)
    assert status == 130, errors
    summary = json.loads((out / "run.json").read_text())
    assert [change.split("@")[0] for change in summary["pins"]] == ["16=0", "16=z", "16=0", "16=z"]
