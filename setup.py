"""Ships the repository's top-level content folders inside the wheel.

The built-in content lives in the top-level folders of the repository (``scenes/``,
``humans/``, ``robots/``, ``agents/``, ``assets/``, ``eval/``); a built wheel carries a copy
of each under ``havln_mj/_data/``, where :mod:`havln_mj.paths` finds it through
``importlib.resources``. An editable install reads them in place.

The collision signal's inner loop is also built as a C extension (``havln_mj.sim._closest``)
where a C compiler is at hand; without one the build goes on and the package uses its numpy
path, which gives the same numbers. Everything else is in ``pyproject.toml``.
"""

import shutil
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
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


class BuildExact(build_ext):
    """``build_ext`` that keeps floating-point operations unfused (as numpy rounds them)."""

    def build_extensions(self) -> None:
        """Builds the extensions, with ``-ffp-contract=off`` on GCC-like compilers."""
        if self.compiler.compiler_type == "unix":
            for ext in self.extensions:
                ext.extra_compile_args = [*ext.extra_compile_args, "-O2", "-ffp-contract=off"]
        super().build_extensions()


setup(
    cmdclass={"build_py": BuildWithContent, "build_ext": BuildExact},
    ext_modules=[
        Extension("havln_mj.sim._closest", ["havln_mj/sim/_closest.c"], optional=True),
        Extension("havln_mj.sim._navigable", ["havln_mj/sim/_navigable.c"], optional=True),
    ],
)
