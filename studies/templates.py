r"""Pages from templates: the numbers in hand-written pages filled from their result JSONs.

A hand-written page (the README, ``docs/*.md``) quotes a measured figure only inside a block::

    <!-- numbers env=benchmarks/results/env.json
    the vector env runs {{ env.rest.vector_env_throws_per_s | ,.0f }} throws/s
    -->
    the vector env runs 1,399 throws/s
    <!-- /numbers -->

Each ``{{ expression | format }}`` of the hidden template is a Python expression over the named
JSONs (keys by ``.name`` or ``["key"]``, the builtins of :data:`HELPERS`), written with the
format spec. A source may name a part of its JSON, keys joined by ``/``:
``rest=benchmarks/results/physics.json#throws_to_rest/Scene()``.
``python -m studies.templates`` rewrites every block from its JSONs; ``--check`` lists
the stale blocks instead (``tests/test_docs.py`` runs it). :func:`study_page` fills a study's
page, ``docs/templates/NAME.md``, the same way from the study's Python objects.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from dice_env.disk import write_atomically
from studies import ROOT

TEMPLATES = ROOT / "docs" / "templates"  # the studies' pages, filled by :func:`study_page`
BLOCK = re.compile(r"<!-- numbers (?P<sources>[^\n]*)\n(?P<template>.*?)-->\n(?P<text>.*?)"
                   r"<!-- /numbers -->", re.S)
FIELD = re.compile(r"\{\{(.+?)\}\}", re.S)
SPEC = re.compile(r"[\w ,.%+<>=^#-]*")  # what may follow the last "|" of a field: a format spec
HELPERS = {f.__name__: f for f in (min, max, len, sum, abs, round, sorted, all, any, enumerate,
                                   zip, range, int, float, str, repr)}


class Tree(dict):
    """A JSON object whose keys read as attributes too (``env.rest.batch``)."""

    def __getattr__(self, name: str) -> object:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None


def wrap(value: object) -> object:
    """JSON objects as :class:`Tree`, lists element-wise, all the way down; the rest as it is."""
    if isinstance(value, dict):
        return Tree({k: wrap(v) for k, v in value.items()})
    if isinstance(value, list):
        return [wrap(v) for v in value]
    return value


@dataclass(frozen=True)
class Block:
    """One filled block of a page: where it is, its sources, its template and its text."""

    page: Path
    line: int
    sources: dict[str, tuple[Path, tuple[str, ...]]]  # name -> (JSON file, keys into it)
    template: str
    text: str

    def render(self) -> str:
        """The block's text as its JSONs give it."""
        names = {}
        for name, (path, keys) in self.sources.items():
            if not path.is_file():
                raise FileNotFoundError(f"{self.where}: {name}={_shown(path)} is not in the "
                                        "repository")
            value = json.loads(path.read_text())
            for key in keys:
                try:
                    value = value[key]
                except (KeyError, TypeError):
                    raise KeyError(f"{self.where}: {name}: {_shown(path)} has no "
                                   f"{'/'.join(keys)}") from None
            names[name] = wrap(value)
        return substitute(self.template, names, self.where)

    @property
    def where(self) -> str:
        """``page:line`` of the block."""
        return f"{_shown(self.page)}:{self.line}"


def substitute(template: str, names: dict[str, object], where: str) -> str:
    """``template`` with each ``{{ expression | format }}`` evaluated over ``names``."""
    scope = {"__builtins__": {}, **HELPERS, **names}

    def field(match: re.Match) -> str:
        expression, sep, spec = match.group(1).rpartition("|")
        if not sep or not SPEC.fullmatch(spec.strip()):  # a "|" inside the expression
            expression, spec = match.group(1), ""
        try:
            value = eval(expression, scope)  # globals: comprehensions see the names
        except Exception as error:
            raise ValueError(f"{where}: {{{{{match.group(1)}}}}}: {error!r}") from None
        return format(value, spec.strip())

    return FIELD.sub(field, template)


def study_page(name: str, namespace: dict[str, object] | None = None, /, **names: object) -> str:
    """The study page ``docs/templates/NAME.md`` filled from ``names``, then ``namespace``.

    A study passes its ``globals()`` as ``namespace``: its template sees its constants and helpers.
    """
    path = TEMPLATES / f"{name}.md"
    scope = {k: v for k, v in (namespace or {}).items() if not k.startswith("__")} | names
    return substitute(path.read_text(), scope, _shown(path))


def _shown(path: Path) -> str:
    return str(path.relative_to(ROOT) if path.is_relative_to(ROOT) else path)


def _block(page: Path, text: str, match: re.Match) -> Block:
    sources = {}
    for item in match.group("sources").split():
        name, sep, path = item.partition("=")
        if not sep or not name.isidentifier():
            raise ValueError(f"{page}: a numbers block names its JSONs as NAME=PATH, not "
                             f"{item!r}")
        path, _, pointer = path.partition("#")
        sources[name] = ROOT / path, tuple(pointer.split("/")) if pointer else ()
    return Block(page, text.count("\n", 0, match.start()) + 1, sources, match.group("template"),
                 match.group("text"))


def blocks(page: Path) -> list[Block]:
    """The filled blocks of a page."""
    text = page.read_text()
    return [_block(page, text, match) for match in BLOCK.finditer(text)]


def pages() -> list[Path]:
    """The pages that may hold blocks: the README and ``docs/``."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("**/*.md"))]


def stale() -> list[str]:
    """``page:line`` of every block whose text is not what its JSONs give."""
    return [b.where for page in pages() for b in blocks(page) if b.render() != b.text]


def fill(page: Path) -> bool:
    """Rewrite the page's blocks from their JSONs; whether anything changed."""
    text = page.read_text()
    new = BLOCK.sub(lambda m: f"<!-- numbers {m['sources']}\n{m['template']}-->\n"
                              f"{_block(page, text, m).render()}<!-- /numbers -->", text)
    if new != text:
        write_atomically(page, new.encode())
    return new != text


def main(argv: list[str] | None = None) -> int:
    """Fill every page's blocks, or with ``--check`` list the stale ones (exit 1 if any)."""
    parser = argparse.ArgumentParser(prog="python -m studies.templates",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="change nothing; list the blocks that differ from their JSONs")
    args = parser.parse_args(argv)
    if args.check:
        differ = stale()
        for where in differ:
            print(f"{where}: differs from its JSONs (python -m studies.templates)")
        return 1 if differ else 0
    for page in pages():
        if fill(page):
            print(f"filled {_shown(page)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
