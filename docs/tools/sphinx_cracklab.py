"""Sphinx extension of the documentation site (docs/conf.py).

- ``.. cracklab-api::`` writes the API reference of the site: for every layer of
  docs/tools/api_page.py (the same public names, in the same order, as docs/reference/api.md) a
  section with an autodoc entry per name (full docstring, members of classes), and the
  ``--help`` text of every ``cracklab`` subcommand. A public name added to api_page.py
  therefore appears on the site without editing a page.
- Docstrings: cracklab's are plain prose with ``code``; the few with numpy-style
  sections (a title underlined with dashes) go through napoleon's NumpyDocstring, and
  ``|x|`` (an absolute value) is text, not a reST substitution.
- References: a reference to a cracklab object that exists but is internal (not on the
  site) is shown as code without a link; one to a name that does not exist stays a
  warning (an error under -W). A Markdown link to the repository's README.md goes to the
  site's copy of it (site/readme.md).
"""
from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import inspect
import re
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx import addnodes
from sphinx.ext.napoleon import Config
from sphinx.ext.napoleon.docstring import NumpyDocstring
from sphinx.transforms.post_transforms import SphinxPostTransform
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

TOOLS = Path(__file__).resolve().parent


def api_page():
    """docs/tools/api_page.py as a module."""
    spec = importlib.util.spec_from_file_location("cracklab_api_page", TOOLS / "api_page.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def autodoc_kind(obj, owner) -> str:
    """The autodoc directive for an object found by api_page.resolve."""
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return "autoexception"
    if inspect.isclass(obj):
        return "autoclass"
    if inspect.ismodule(obj):
        return "automodule"
    if callable(obj) and owner is None:
        return "autofunction"
    return "autodata"


def top_level(names: list[str]) -> list[str]:
    """The names that are not members of another listed name (those are documented
    with their class)."""
    listed = set(names)
    return [n for n in names if "." not in n or n.rsplit(".", 1)[0] not in listed]


def command_help(name: str) -> str:
    """The ``--help`` text of ``cracklab NAME``."""
    import click

    from cracklab.cli import main

    cmd = main.commands[name]
    with click.Context(cmd, info_name=f"cracklab {name}", max_content_width=88, terminal_width=88) as ctx:
        return cmd.get_help(ctx)


def rst_inline(text: str) -> str:
    """api_page's Markdown inline code as reST."""
    return text.replace("`", "``")


def reference_lines() -> list[str]:
    page = api_page()
    lines: list[str] = []
    for title, layer, names in page.groups():
        lines += [title, "-" * len(title), "", f"Layer: {rst_inline(layer)}.", ""]
        for name in top_level(names):
            if name.startswith("cracklab "):
                cmd = name.split(" ", 1)[1]
                lines += [f"``{name}``", "~" * (len(name) + 4), "", ".. code-block:: text", ""]
                lines += [f"   {line}".rstrip() for line in command_help(cmd).splitlines()]
                lines.append("")
                continue
            owner, obj = page.resolve(name)
            lines += [f".. {autodoc_kind(obj, owner)}:: {name}", ""]
    return lines


class CracklabAPI(SphinxDirective):
    """``.. cracklab-api::``: the API reference, by layer (see the module docstring)."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        self.env.note_dependency(str(TOOLS / "api_page.py"))
        content = StringList()
        for i, line in enumerate(reference_lines()):
            content.append(line, "<cracklab-api>", i)
        node = nodes.section()
        node.document = self.state.document
        nested_parse_with_titles(self.state, content, node)
        return node.children


# ----------------------------------------------------------------------------- docstrings
NUMPY_SECTION = re.compile(r"^[ \t]*(Parameters|Returns|Yields|Raises|Warns|Notes|Examples|See Also|"
                           r"Attributes|Methods|References|Other Parameters)[ \t]*\n[ \t]*-{3,}[ \t]*$", re.M)
#: napoleon's options for the numpy-style docstrings: parameter types as text (they are
#: descriptions such as ``float > 0``, not names to link)
NAPOLEON = Config(napoleon_use_param=False, napoleon_use_rtype=False, napoleon_use_ivar=True,
                  napoleon_preprocess_types=False)
#: |x|, an absolute value in a docstring (reST would read a substitution)
ABSOLUTE = re.compile(r"(?<![\\|])\|(?=[^|\s])([^|\n`]*?[^|\s\\])\|(?![|_])")
#: a cross-reference role in a docstring
ROLE = re.compile(r":(func|meth|class|data|attr|obj|exc|mod):`(~?)([\w.]+)`")


def table_row(line: str) -> bool:
    s = line.strip()
    return s.startswith("+-") or (s.startswith("|") and s.endswith("|") and s.count("|") > 2)


def process_docstring(app, what, name, obj, options, lines):
    """autodoc-process-docstring: numpy sections through napoleon; |x| as text; a
    docstring whose first line ends with :: keeps its literal block indented; a
    reference relative to the object's module made absolute."""
    if lines and lines[0].rstrip().endswith("::") and len(lines) > 2 and not lines[1].strip() \
            and lines[2][:1] not in ("", " "):
        lines[2:] = [f"    {line}" if line.strip() else line for line in lines[2:]]
    if inspect.isclass(obj) and dataclasses.is_dataclass(obj) and lines \
            and lines[0].startswith(f"{obj.__name__}("):
        lines[:] = []  # the signature dataclasses writes when there is no docstring
    text = "\n".join(lines)
    if what in ("function", "method", "class", "exception") and NUMPY_SECTION.search(text):
        lines[:] = NumpyDocstring(lines, NAPOLEON, app, what, name, obj, options).lines()
    module = getattr(inspect.unwrap(obj) if callable(obj) else obj, "__module__", None)
    if module is None and isinstance(obj, property) and obj.fget is not None:
        module = obj.fget.__module__
    qualname = getattr(obj, "__qualname__", "")
    cls = qualname.rsplit(".", 1)[0] if "." in qualname else None

    def absolute(m):
        role, tilde, target = m.groups()
        if target.startswith("cracklab") or cracklab_object(target, None, None) is not None or not module:
            return m.group(0)
        for full in filter(None, (f"{module}.{cls}.{target}" if cls else None, f"{module}.{target}")):
            if cracklab_object(full, None, None) is not None:
                return f":{role}:`{target} <{full}>`" if not tilde else f":{role}:`~{full}`"
        return m.group(0)

    for i, line in enumerate(lines):
        if not table_row(line):
            line = ABSOLUTE.sub(r"\\|\1\\|", line)
        lines[i] = ROLE.sub(absolute, line)


# ----------------------------------------------------------------------------- references
def cracklab_object(target: str, module: str | None, cls: str | None):
    """The cracklab object a reference names (absolute, or relative to the module and
    class it is written in), or None."""
    candidates = [target]
    if module:
        candidates += [f"{module}.{cls}.{target}" if cls else None, f"{module}.{target}"]
    for dotted in filter(None, candidates):
        if not dotted.startswith("cracklab"):
            continue
        parts = dotted.split(".")
        for k in range(len(parts), 0, -1):
            try:
                obj = importlib.import_module(".".join(parts[:k]))
            except ImportError:
                continue
            try:
                for attr in parts[k:]:
                    obj = getattr(obj, attr)
            except AttributeError:
                break
            return obj
    return None


def internal_reference(app, env, node, contnode):
    """missing-reference: an internal cracklab object is shown as code, unlinked."""
    if node.get("refdomain") != "py":
        return None
    if cracklab_object(node["reftarget"], node.get("py:module"), node.get("py:class")) is not None:
        return contnode
    return None


class ReadmeLinks(SphinxPostTransform):
    """[text](../README.md) (a file outside docs/) goes to the site's copy, site/readme."""

    default_priority = 8  # before myst's reference resolver (9)

    def run(self, **kwargs) -> None:
        readme = str(Path(self.env.srcdir).parent / "README")
        for node in self.document.findall(addnodes.pending_xref):
            if node.get("reftype") == "myst" and node.get("refdomain") == "doc" \
                    and node.get("reftarget") == readme:
                node["reftarget"] = "site/readme"


def setup(app):
    app.add_directive("cracklab-api", CracklabAPI)
    app.connect("autodoc-process-docstring", process_docstring)
    app.connect("missing-reference", internal_reference)
    app.add_post_transform(ReadmeLinks)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
