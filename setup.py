"""Ships the repository's top-level content folders inside the wheel.

The built-in content lives in the top-level folders of the repository (``scenes/``,
``humans/``, ``robots/``, ``agents/``, ``assets/``, ``eval/``); a built wheel carries a copy
of each under ``havln_mj/_data/``, where :mod:`havln_mj.paths` finds it through
``importlib.resources``. An editable install reads them in place. Everything else is in
``pyproject.toml``.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

CONTENT = ("scenes", "humans", "robots", "agents", "assets", "eval")
_SKIP = shutil.ignore_patterns("__pycache__", "*.pyc", ".*")


class BuildWithContent(build_py):
    """``build_py`` that also copies the content folders into ``havln_mj/_data``."""

    def run(self) -> None:
        """Builds the package, then copies the content (not for editable installs)."""
        super().run()
        if self.editable_mode:
            return
        root = Path(__file__).resolve().parent
        target = Path(self.build_lib) / "havln_mj" / "_data"
        for name in CONTENT:
            if (root / name).is_dir():
                shutil.copytree(root / name, target / name, ignore=_SKIP, dirs_exist_ok=True)


setup(cmdclass={"build_py": BuildWithContent})
