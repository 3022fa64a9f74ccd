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
