"""MkDocs hook: every Sphinx-style reference in the code's docstrings names something that exists.

``:func:`dice_env.physics.kernel.advance```, ``:class:`Scene``` and the like are resolved against
the package (a bare name against the module it is written in); the build stops, listing each
reference that names nothing, so that a renamed or removed function cannot leave its old name
in the documentation. Run by ``mkdocs build`` (``hooks:`` in ``mkdocs.yml``) and by
``tests/test_docs.py``.
"""

from __future__ import annotations

import importlib
import pkgutil
import re
import sys
from pathlib import Path

ROLE = re.compile(r":(?:func|class|mod|meth|attr|data|obj|exc):`~?([A-Za-z_][\w.]*)(?:\(\))?`")
PACKAGES = ("dice_env", "agents", "studies")


def _resolve(name: str, module: object) -> bool:
    """Whether ``name`` is an attribute path from a module it starts with, or from ``module``.

    A bare name may also be a method or attribute of a class of ``module``, named inside it.
    """
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            target = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        if _walk(target, parts[cut:]):
            return True
    classes = [c for c in vars(module).values() if isinstance(c, type)]
    return any(_walk(scope, parts) for scope in (module, *classes))


def _walk(target: object, parts: list[str]) -> bool:
    for part in parts:
        if not hasattr(target, part):
            annotations = getattr(target, "__annotations__", {})
            if part not in annotations and part not in getattr(target, "_fields", ()):
                return False
            return True  # a dataclass or NamedTuple field
        target = getattr(target, part)
    return True


def unresolved(root: Path) -> list[str]:
    """``path:line: reference`` for every reference in ``PACKAGES`` that names nothing."""
    root, missing = root.resolve(), []
    if str(root) not in sys.path:  # studies/ is not installed: it imports from the checkout
        sys.path.insert(0, str(root))
    for package in PACKAGES:
        for info in pkgutil.walk_packages([str(root / package)], prefix=f"{package}."):
            if info.name.endswith("__main__"):
                continue
            module = importlib.import_module(info.name)
            path = Path(module.__file__)
            text = path.read_text()
            for match in ROLE.finditer(text):
                if not _resolve(match.group(1), module):
                    line = text.count("\n", 0, match.start()) + 1
                    missing.append(f"{path.relative_to(root)}:{line}: {match.group(0)}")
        package_init = importlib.import_module(package)
        text = Path(package_init.__file__).read_text()
        for match in ROLE.finditer(text):
            if not _resolve(match.group(1), package_init):
                missing.append(f"{package}/__init__.py: {match.group(0)}")
    return missing


def on_pre_build(config: object) -> None:
    """Stop the build on a reference that names nothing."""
    from mkdocs.exceptions import PluginError

    missing = unresolved(Path(config["config_file_path"]).parent)
    if missing:
        raise PluginError("docstring references to names that do not exist:\n  "
                          + "\n  ".join(missing))
