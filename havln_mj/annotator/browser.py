"""A headless Chromium to drive pages with: Debian's ``chromium`` and ``chromedriver``.

Used by the end-to-end tests of the annotation page and the video files, and to make the
documentation's screenshot. The browser is the system's (``apt-get install chromium
chromium-driver``; ``$HAVLN_CHROMIUM`` and ``$HAVLN_CHROMEDRIVER`` override where they are);
nothing is downloaded. It runs with a fresh profile, no sandbox (containers run as root), no
GPU and no background traffic.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from havln_mj.errors import DependencyNotInstalledError, MissingDataError

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--autoplay-policy=no-user-gesture-required",
)


def _find(env: str, names: tuple[str, ...]) -> Path | None:
    given = os.environ.get(env)
    if given:
        return Path(given) if Path(given).is_file() else None
    for name in names:
        found = shutil.which(name)
        if found:
            return Path(found)
    return None


def browser_paths() -> tuple[Path, Path]:
    """The Chromium binary and its chromedriver.

    Raises:
        MissingDataError: Either is not installed (naming the install command).
    """
    chromium = _find("HAVLN_CHROMIUM", ("chromium", "chromium-browser"))
    driver = _find("HAVLN_CHROMEDRIVER", ("chromedriver",))
    if chromium is None or driver is None:
        missing = [n for n, p in (("chromium", chromium), ("chromedriver", driver)) if p is None]
        raise MissingDataError(
            f"{' and '.join(missing)} not found (install with 'apt-get install chromium "
            "chromium-driver', or set $HAVLN_CHROMIUM / $HAVLN_CHROMEDRIVER)"
        )
    return chromium, driver


@contextlib.contextmanager
def headless_chromium(width: int = 1280, height: int = 900) -> Iterator:
    """A selenium ``WebDriver`` on a headless Chromium with a fresh profile, closed on exit.

    Args:
        width: Window width in pixels.
        height: Window height in pixels.

    Raises:
        DependencyNotInstalledError: selenium is not installed (it comes with ``.[dev]``).
        MissingDataError: Chromium or chromedriver is not installed.
    """
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        raise DependencyNotInstalledError(
            "driving a browser needs selenium: pip install 'havln_mj[dev]'"
        ) from None
    chromium, driver_path = browser_paths()
    with tempfile.TemporaryDirectory(prefix="havln-chromium-") as profile:
        options = webdriver.ChromeOptions()
        options.binary_location = str(chromium)
        for flag in (*FLAGS, f"--user-data-dir={profile}", f"--window-size={width},{height}"):
            options.add_argument(flag)
        driver = webdriver.Chrome(service=Service(str(driver_path)), options=options)
        try:
            yield driver
        finally:
            driver.quit()


class AnnotatorPage:
    """The annotation page in a browser, driven the way a person uses it (clicks, choices).

    Args:
        driver: A selenium ``WebDriver`` (see :func:`headless_chromium`).
        url: The page's address (``AnnotationServer.url``).
        timeout: Seconds to wait for the page to answer each step.
    """

    def __init__(self, driver: object, url: str, timeout: float = 60.0) -> None:
        from selenium.webdriver.support.ui import WebDriverWait

        self.driver = driver
        self._wait = WebDriverWait(driver, timeout)
        driver.get(url)
        self.wait_status("ready")
        self.wait_view()

    def _el(self, css: str) -> object:
        from selenium.webdriver.common.by import By

        return self.driver.find_element(By.CSS_SELECTOR, css)

    def status(self) -> str:
        """The status line's text."""
        return self._el("#status").text

    def wait_status(self, prefix: str) -> str:
        """Waits until the status line starts with ``prefix`` (or shows an error)."""
        failed = lambda: "error" in (self._el("#status").get_attribute("class") or "")  # noqa: E731
        self._wait.until(lambda d: self.status().startswith(prefix) or failed())
        if not self.status().startswith(prefix):
            raise AssertionError(f"page says {self.status()!r}, expected {prefix!r}...")
        return self.status()

    def wait_view(self) -> None:
        """Waits until the agent's view image has loaded."""
        self._wait.until(
            lambda d: d.execute_script(
                "const i = document.getElementById('view');return i.complete && i.naturalWidth > 0"
            )
        )

    def click_viewpoint(self, viewpoint: str) -> None:
        """Clicks a viewpoint on the map."""
        self._el(f'circle.vp[data-id="{viewpoint}"]').click()

    def choose(self, activity: str | None = None, model: int | None = None,
               facing_deg: float | None = None) -> None:  # fmt: skip
        """Sets the person form: activity (of the viewpoint's room kind), motion, facing."""
        from selenium.webdriver.common.keys import Keys
        from selenium.webdriver.support.ui import Select

        if activity is not None:
            code = self.driver.execute_script(
                "const r = state.catalog.regions.find("
                "(r) => r.activities.some((a) => a.id === arguments[0])); return r && r.code;",
                activity,
            )
            select = Select(self._el("#region"))
            if select.first_selected_option.get_attribute("value") != code:
                select.select_by_value(code)
            Select(self._el("#activity")).select_by_value(activity)
        if model is not None:
            Select(self._el("#model")).select_by_value(str(model))
        if facing_deg is not None:
            box = self._el("#heading")
            box.clear()
            box.send_keys(f"{facing_deg:g}", Keys.TAB)

    def _button(self, name: str, then: str) -> str:
        self._el(f"#{name}").click()
        return self.wait_status(then)

    def place(self, viewpoint: str) -> str:
        """Clicks 'Place person here' (for the selected viewpoint)."""
        return self._button("place", f"placed a person on {viewpoint}")

    def move(self, to: str) -> str:
        """Clicks 'Move here' (the selected person to the selected viewpoint)."""
        return self._button("move", "moved a person from")

    def delete(self) -> str:
        """Clicks 'Delete' (the selected person)."""
        return self._button("delete", "deleted the person on")

    def new_person(self) -> None:
        """Clicks 'New person' (deselects the person)."""
        self._el("#deselect").click()

    def save(self) -> str:
        """Clicks 'Save'; returns the status line."""
        return self._button("save", "saved")

    def preview(self) -> dict:
        """Waits for the preview video's metadata; its duration (s), width and error code."""
        return self.driver.execute_async_script(
            """const done = arguments[arguments.length - 1];
            const v = document.getElementById('preview');
            const report = () => done({duration: v.duration, width: v.videoWidth,
                                       error: v.error && v.error.code});
            if (v.readyState >= 1 || v.error) report();
            else { v.addEventListener('loadedmetadata', report);
                   v.addEventListener('error', report); }"""
        )
