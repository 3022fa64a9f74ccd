"""The documentation site builds from the docstrings and guides with zero warnings."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

# The whole site from the docstrings: about 30 s of CPU.
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site built in strict mode (warnings are errors, every reference must resolve)."""
    missing = [m for m in ("sphinx", "myst_parser", "furo") if importlib.util.find_spec(m) is None]
    if missing:
        pytest.skip(
            f"the docs tools are not installed ({', '.join(missing)}): pip install -e '.[docs]'"
        )
    out = tmp_path_factory.mktemp("site")
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-E", "-q", "-b", "html"]
    cmd += ["-d", str(out / ".doctrees"), str(DOCS), str(out)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=900)
    # -W makes any warning (a broken reference, a bad docstring section) fail the build.
    assert done.returncode == 0, done.stderr
    return out


def test_every_page_is_built(site: Path) -> None:
    pages = {p.relative_to(DOCS).with_suffix(".html") for p in DOCS.rglob("*.md")}
    pages |= {p.relative_to(DOCS).with_suffix(".html") for p in DOCS.rglob("*.rst")}
    assert pages and all((site / p).is_file() for p in pages)


def test_reference_is_read_from_the_docstrings(site: Path) -> None:
    page = (site / "api/simulator.html").read_text()
    assert 'id="havln_mj.sim.simulator.Simulator.makeAction"' in page
    # A Google-style Args section becomes a parameter list, and a cross-reference a link.
    assert re.search(r"Parameters.*collision_distance", page, re.S)
    assert 'href="#havln_mj.sim.batch.WAIT_S"' in page


def test_guides_link_into_the_reference(site: Path) -> None:
    for guide in (site / "guides").glob("*.html"):
        assert "api/" in guide.read_text(), f"{guide.name} links to no reference page"


def test_pictures_are_copied(site: Path) -> None:
    for page in site.rglob("*.html"):
        for src in re.findall(r'<img[^>]+src="([^"]+)"', page.read_text()):
            assert "://" in src or (page.parent / src).is_file(), f"{page.name}: {src}"
