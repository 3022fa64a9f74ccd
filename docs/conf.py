"""Sphinx configuration of the havln_mj documentation.

Build it with ``sphinx-build -W --keep-going -n -b html docs build/docs`` (the ``docs`` extra).
The reference is read from the package's Google-style docstrings (autodoc + napoleon); the
guides are Markdown (MyST). Nothing is fetched from the network: no intersphinx inventories,
and the theme ships its own assets.
"""

from __future__ import annotations

import importlib.util
import pkgutil
import sys
import typing

from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.parsing import nested_parse_to_nodes
from sphinx.util.typing import stringify_annotation

import havln_mj

project = "havln_mj"
author = "havln_mj authors"
copyright = "havln_mj authors"
release = version = havln_mj.__version__

extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "myst_parser"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]
html_theme = "furo"
html_title = f"havln_mj {release}"
html_static_path: list[str] = []

myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3

napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_attr_annotations = True
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented_params"
autodoc_preserve_defaults = True

# Optional extras that are not installed are mocked, so the reference builds from the
# ``docs`` extra alone; with ``dev`` installed nothing is mocked.
_OPTIONAL = ["torch", "gymnasium", "dm_env", "dm_control", "ray"]
autodoc_mock_imports = [name for name in _OPTIONAL if importlib.util.find_spec(name) is None]

# Types from Python's library and other projects: no inventories are fetched (the build works
# offline), so their names stay plain text.
_OTHERS = ["np", "numpy", "npt", "mujoco", "nn", "Tensor", "gym", "specs", "Path"]
_OTHERS += ["scipy", "trimesh", "cv2", "matplotlib", "PIL", "shapely", "tqdm", *_OPTIONAL]
nitpick_ignore_regex = [
    (r"py:.*", rf"({'|'.join(sorted({*sys.stdlib_module_names, *_OTHERS}))})(\..*)?"),
    # Private names in annotations are left undocumented on purpose.
    (r"py:.*", r"(.*\.)?_[A-Za-z]\w*"),
]

_log = logging.getLogger(__name__)


def _public_modules() -> list[str]:
    """Every module of the package that the reference documents (not ``__main__``, not private)."""
    names = ["havln_mj"]
    for info in pkgutil.walk_packages(havln_mj.__path__, "havln_mj."):
        leaf = info.name.rsplit(".", 1)[-1]
        if not leaf.startswith("_"):
            names.append(info.name)
    return sorted(names)


class HavlnModules(SphinxDirective):
    """``.. havln-modules:: a.b a.c.*``: a section with the reference of each named module.

    A name ending in ``.*`` stands for the package and every public module under it.
    """

    required_arguments = 1
    final_argument_whitespace = True

    def run(self) -> list:
        """The sections of the named modules."""
        modules = _public_modules()
        chosen: list[str] = []
        for pattern in self.arguments[0].split():
            if pattern.endswith(".*"):
                root = pattern[:-2]
                found = [m for m in modules if m == root or m.startswith(root + ".")]
            else:
                found = [m for m in modules if m == pattern]
            if not found:
                _log.warning("havln-modules: no module %s", pattern, location=self.get_location())
            chosen += [m for m in found if m not in chosen]
        claimed = self.env.domaindata.setdefault("havln_modules", {})
        content = StringList()
        for name in chosen:
            claimed.setdefault(name, []).append(self.env.docname)
            title = f"``{name}``"
            lines = [title, "-" * len(title), "", f".. automodule:: {name}"]
            if importlib.util.find_spec(name).submodule_search_locations is not None:
                # A package's ``__all__`` re-exports its modules' names: document them once,
                # where they are defined.
                lines.append("   :ignore-module-all:")
            for offset, line in enumerate([*lines, ""]):
                content.append(line, f"<{self.env.docname}: {name}>", offset)
        return nested_parse_to_nodes(self.state, content, allow_section_headings=True)


def _check_coverage(app, env) -> None:
    """Warns about modules on no reference page, or on more than one."""
    claimed = env.domaindata.get("havln_modules", {})
    for name in _public_modules():
        pages = claimed.get(name, [])
        if not pages:
            _log.warning(
                "module %s is on no page: name it in a havln-modules line of docs/api/", name
            )
        elif len(pages) > 1:
            _log.warning("module %s is on several pages: %s", name, ", ".join(pages))


def _class_typehints(app, what: str, name: str, obj: object, *_: object) -> None:
    """Records a class's parameter types from its ``__init__``, evaluated in its own module.

    Sphinx reads a class signature's annotations as the strings that ``from __future__ import
    annotations`` leaves, so a bare name (``Crowd``) could link to a namesake elsewhere.
    """
    if what != "class":
        return
    try:
        hints = typing.get_type_hints(obj.__init__)
    except Exception:  # an annotation that cannot be evaluated: Sphinx's record stands
        return
    recorded = app.env.current_document.autodoc_annotations.setdefault(name, {})
    for param, hint in hints.items():
        if param != "return":
            recorded[param] = stringify_annotation(hint, "smart")


def _skip_tuple_fields(app, what: str, name: str, obj: object, skip: bool, *_: object):
    """Leaves a NamedTuple's field accessors out: its ``Attributes:`` section documents them."""
    if type(obj).__name__ == "_tuplegetter":
        return True
    return None


def _purge(app, env, docname: str) -> None:
    """Forgets what a page claimed before it is read again."""
    for pages in env.domaindata.get("havln_modules", {}).values():
        while docname in pages:
            pages.remove(docname)


def setup(app) -> dict:
    """Registers the reference directive and the coverage check."""
    app.add_directive("havln-modules", HavlnModules)
    app.connect("autodoc-process-signature", _class_typehints, priority=600)
    app.connect("autodoc-skip-member", _skip_tuple_fields)
    app.connect("env-purge-doc", _purge)
    app.connect("env-check-consistency", _check_coverage)
    return {"parallel_read_safe": False}
