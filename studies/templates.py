r"""The docs' measured numbers, written once and filled from their result JSONs.

Two forms, both written by ``python -m studies.templates``; ``--check`` changes nothing and
lists what differs from its JSONs instead (``tests/test_docs.py`` runs it):

- **Generated files.** A table or a paragraph that carries measured numbers is a file
  ``docs/generated/NAME.md``, rendered by a function of :mod:`studies.docs_numbers` from its
  JSONs (every computation and verdict in Python) and included by the hand-written page with
  ``--8<-- "generated/NAME.md"`` (``pymdownx.snippets``, ``docs`` in its ``base_path``). Its
  first line (:data:`HEADER`) names the command that writes it and the JSONs it reads; being a
  snippet section marker, that line is left out of the page. The file ends without a newline,
  so that an include may continue a paragraph.
- **Fields.** The README is read raw (GitHub, PyPI) and includes nothing: there a sentence that
  quotes a figure stands in a block, its hidden template above its filled copy::

      <!-- numbers cold=benchmarks/results/cold_start.json
      the precompile takes {{ cold.suite.seconds.precompile | .0f }} s
      -->
      the precompile takes 69 s
      <!-- /numbers -->

  A field is one value and a format spec: a source's name, keys (``.key``; ``.0`` for a list's
  first item) and, after ``|``, the spec; no expression. A source may name a part of its JSON,
  keys joined by ``/``: ``rest=benchmarks/results/physics.json#throws_to_rest/Scene()``. A
  value computed from a JSON (a sum, a verdict) is computed in Python
  (:data:`studies.docs_numbers.VALUES`) and read as a key of that JSON.

A study (``python -m studies NAME``) writes its page's files the same way: its run's numbers as
``OUT/NAME.json``, its files rendered from them (:func:`write_study`); ``--check`` renders the
committed files again from ``docs/NAME.json``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from dice_env.disk import write_atomically
from studies import ROOT

GENERATED = ROOT / "docs" / "generated"  # the generated files, included by the pages
HEADER = ("<!-- --8<-- [start:generated] written by {command}{sources}: do not edit "
          "(snippets leaves this line out) -->\n")
INCLUDE = re.compile(r'^--8<-- "generated/(?P<name>[\w-]+)\.md"$', re.M)
BLOCK = re.compile(r"<!-- numbers (?P<sources>[^\n]*)\n(?P<template>.*?)-->\n(?P<text>.*?)"
                   r"<!-- /numbers -->", re.S)
ANY_FIELD = re.compile(r"\{\{(.*?)\}\}", re.S)
FIELD = re.compile(r"\s*(?P<path>[A-Za-z_]\w*(?:\.\w+)*)\s*(?:\|(?P<spec>[\w ,.%+<>=^#-]*))?")


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


def shown(path: Path) -> str:
    """``path`` relative to the checkout where it is inside it."""
    return str(path.relative_to(ROOT) if path.is_relative_to(ROOT) else path)


def load(source: str, where: str = "") -> object:
    """The JSON (or its part) that ``source``, ``PATH[#key/key]``, names, as a :class:`Tree`."""
    from studies.docs_numbers import VALUES

    path, _, pointer = source.partition("#")
    if not (ROOT / path).is_file():
        raise FileNotFoundError(f"{where}{path} is not in the repository")
    value = json.loads((ROOT / path).read_text())
    for key in pointer.split("/") if pointer else ():
        try:
            value = value[key]
        except (KeyError, TypeError):
            raise KeyError(f"{where}{path} has no {pointer}") from None
    value = wrap(value)
    if source in VALUES:
        computed = VALUES[source](value)
        if clash := sorted(set(computed) & set(value)):
            raise KeyError(f"{source}: computed values {clash} hide the JSON's own keys")
        value = Tree(value | computed)
    return value


def field(names: dict[str, object], text: str, where: str) -> str:
    """One field's text: ``name.key.key | spec`` looked up in ``names`` and formatted."""
    match = FIELD.fullmatch(text)
    if match is None:
        raise ValueError(f"{where}: {{{{{text}}}}}: a field is one value and a format "
                         "(name.key | spec), not an expression: compute it in Python "
                         "(studies.docs_numbers.VALUES)")
    first, *keys = match["path"].split(".")
    try:
        value = names[first]
        for key in keys:
            value = value[int(key)] if isinstance(value, list) else value[key]
    except (KeyError, IndexError, ValueError, TypeError):
        raise KeyError(f"{where}: {{{{{text}}}}}: no such value") from None
    return format(value, (match["spec"] or "").strip())


def computes(template: str) -> list[str]:
    """The fields of ``template`` that are not one value and a format: expressions."""
    return [m[0] for m in ANY_FIELD.finditer(template) if FIELD.fullmatch(m[1]) is None]


@dataclass(frozen=True)
class Block:
    """One filled block of a page: where it is, its sources, its template and its text."""

    page: Path
    line: int
    sources: dict[str, str]  # name -> PATH[#key/key]
    template: str
    text: str

    def render(self) -> str:
        """The block's text as its JSONs give it."""
        names = {name: load(source, f"{self.where}: {name}=") for name, source in
                 self.sources.items()}
        return ANY_FIELD.sub(lambda m: field(names, m[1], self.where), self.template)

    @property
    def where(self) -> str:
        """``page:line`` of the block."""
        return f"{shown(self.page)}:{self.line}"


def _block(page: Path, text: str, match: re.Match) -> Block:
    sources = {}
    for item in match.group("sources").split():
        name, sep, source = item.partition("=")
        if not sep or not name.isidentifier():
            raise ValueError(f"{page}: a numbers block names its JSONs as NAME=PATH, not "
                             f"{item!r}")
        sources[name] = source
    return Block(page, text.count("\n", 0, match.start()) + 1, sources, match.group("template"),
                 match.group("text"))


def blocks(page: Path) -> list[Block]:
    """The filled blocks of a page."""
    text = page.read_text()
    return [_block(page, text, match) for match in BLOCK.finditer(text)]


def pages() -> list[Path]:
    """The pages that may hold blocks: the README and ``docs/``."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("**/*.md"))]


def fill(page: Path) -> bool:
    """Rewrite the page's blocks from their JSONs; whether anything changed."""
    text = page.read_text()
    new = BLOCK.sub(lambda m: f"<!-- numbers {m['sources']}\n{m['template']}-->\n"
                              f"{_block(page, text, m).render()}<!-- /numbers -->", text)
    if new != text:
        write_atomically(page, new.encode())
    return new != text


def renderers() -> dict[str, object]:
    """Every generated file's :class:`studies.docs_numbers.Generated`, the studies' included."""
    from studies import docs_numbers

    for module in docs_numbers.STUDY_MODULES:  # their renderers register themselves on import
        importlib.import_module(module)
    return docs_numbers.GENERATED


def generated_text(name: str, renderer: object | None = None,
                   jsons: dict[str, object] | None = None) -> str:
    """The file ``docs/generated/NAME.md`` as its JSONs give it: header and rendered text.

    ``jsons``: the sources' values, by keyword (a study's fresh numbers), instead of the files.
    """
    renderer = renderer or renderers()[name]
    if jsons is None:
        jsons = {arg: load(source, f"generated/{name}.md: {arg}=")
                 for arg, source in renderer.sources.items()}
    sources = ", ".join(dict.fromkeys(s.partition("#")[0] for s in renderer.sources.values()))
    return (HEADER.format(command=renderer.command, sources=f" from {sources}" if sources else "")
            + renderer.render(**{k: wrap(v) for k, v in jsons.items()}).rstrip("\n"))


def expand(page: str, folder: Path) -> str:
    """``page`` as the docs show it, its includes replaced by the files of ``folder``.

    Each ``--8<-- "generated/NAME.md"`` becomes ``folder/NAME.md``, its header left out.
    """
    return INCLUDE.sub(lambda m: (folder / f"{m['name']}.md").read_text().partition("\n")[2],
                       page)


def write_study(out: Path, page: str, names: list[str],
                jsons: dict[str, object] | None = None) -> None:
    """Write a study's generated files ``names``, rendered from its JSONs, into ``out``.

    From ``jsons`` (the run's numbers, by the renderers' keywords) or else the committed JSONs;
    see :func:`write_files`.
    """
    files = renderers()
    write_files(out, page, {name: generated_text(name, files[name], jsons) for name in names})


def write_files(out: Path, page: str, texts: dict[str, str]) -> None:
    """Write a study's generated files (name -> text, header included) to ``out/generated/``.

    Outside ``docs/`` (a quick run, another ``--out``) also the page ``out/PAGE.md``: the
    hand-written ``docs/PAGE.md`` with those files included, to be read whole.
    """
    (out / "generated").mkdir(parents=True, exist_ok=True)
    for name, text in texts.items():
        path = out / "generated" / f"{name}.md"
        if not path.is_file() or path.read_text() != text:
            write_atomically(path, text.encode())
    if out.resolve() != GENERATED.parent:
        text = expand((GENERATED.parent / f"{page}.md").read_text(), out / "generated")
        write_atomically(out / f"{page}.md", text.encode())


def stale() -> list[str]:
    """Each block (``page:line``) and generated file not what its JSONs give."""
    differ = [b.where for page in pages() for b in blocks(page) if b.render() != b.text]
    for name in renderers():
        path = GENERATED / f"{name}.md"
        if not path.is_file() or path.read_text() != generated_text(name):
            differ.append(shown(path))
    return differ


def write_generated() -> list[Path]:
    """Write every generated file whose text differs from its JSONs'; the files written."""
    written = []
    GENERATED.mkdir(exist_ok=True)
    for name in renderers():
        path, text = GENERATED / f"{name}.md", generated_text(name)
        if not path.is_file() or path.read_text() != text:
            write_atomically(path, text.encode())
            written.append(path)
    return written


def main(argv: list[str] | None = None) -> int:
    """Write the generated files and fill the blocks; ``--check``: list the stale ones instead.

    Exit 1 if ``--check`` finds any.
    """
    parser = argparse.ArgumentParser(prog="python -m studies.templates",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="change nothing; list the blocks and generated files that differ "
                        "from their JSONs")
    args = parser.parse_args(argv)
    if args.check:
        differ = stale()
        for where in differ:
            print(f"{where}: differs from its JSONs (python -m studies.templates)")
        return 1 if differ else 0
    for path in write_generated():
        print(f"wrote {shown(path)}")
    for page in pages():
        if fill(page):
            print(f"filled {shown(page)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
