"""The import graph of the package and the agents points one way: no cycle, no edge upward.

Every import counts: at the top, inside functions, and under ``if TYPE_CHECKING``.
"""

import ast
import graphlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _modules() -> dict[str, Path]:
    """Module name -> file, for agents/, benchmarks/ and dice_env/ (a package: its name)."""
    files = [*ROOT.glob("agents/*.py"), *ROOT.glob("benchmarks/*.py"),
             *ROOT.glob("dice_env/**/*.py")]
    names = {}
    for path in files:
        parts = path.relative_to(ROOT).with_suffix("").parts
        names[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return names


def _imports(path: Path, module: str, modules: dict[str, Path]) -> set[str]:
    """The modules of ``modules`` that ``path`` imports anywhere (functions, type hints)."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names = set()
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join([*parent, base] if base else parent)
            names |= {f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base
                      for alias in node.names}
    found = set()
    for name in names:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        if name and name != module:
            found.add(name)
    return found


def test_no_import_cycle():
    modules = _modules()
    graph = {m: _imports(path, m, modules) for m, path in modules.items()}
    graphlib.TopologicalSorter(graph).prepare()  # raises CycleError naming the cycle


def test_the_table_is_the_bottom_layer():
    modules = _modules()
    assert _imports(modules["dice_env.model.table"], "dice_env.model.table", modules) == {
        "dice_env.model.checks"}


def test_the_core_imports_no_study_agent_or_benchmark():
    # the model, the physics, the simulation and the envs sit below the studies and agents
    modules = _modules()
    for module, path in modules.items():
        if not module.startswith("dice_env") or module.startswith("dice_env.studies"):
            continue
        above = {m for m in _imports(path, module, modules)
                 if m.startswith(("dice_env.studies", "agents", "benchmarks"))}
        assert not above, f"{module} imports {above}"


# The layers, bottom up: a module imports from its own layer and from those listed for it only
# (the package itself, ``dice_env``, stands for the names it exports: the model, the
# simulation and the envs).
LAYERS = {
    "dice_env.model": set(),
    "dice_env.physics": set(),
    "dice_env.intervals": set(),
    "dice_env.markdown": set(),
    "dice_env.provenance": set(),
    "dice_env.simulation": {"dice_env.model", "dice_env.physics"},
    "dice_env.throws": {"dice_env.model", "dice_env.simulation", "dice_env.intervals"},
    "dice_env.envs": {"dice_env.model", "dice_env.simulation"},
    "dice_env.viewer": {"dice_env", "dice_env.model", "dice_env.simulation", "dice_env.envs"},
    "dice_env.studies": {"dice_env", "dice_env.model", "dice_env.physics", "dice_env.simulation",
                         "dice_env.envs", "dice_env.intervals", "dice_env.markdown",
                         "dice_env.provenance", "dice_env.throws"},
}


def _layer(module: str) -> str:
    return next((layer for layer in LAYERS if module == layer or module.startswith(layer + ".")),
                module)


def test_each_layer_imports_only_the_layers_below_it():
    modules = _modules()
    for module, path in modules.items():
        if _layer(module) not in LAYERS:
            continue
        allowed = LAYERS[_layer(module)] | {_layer(module)}
        wrong = {m for m in _imports(path, module, modules)
                 if m.startswith("dice_env") and _layer(m) not in allowed}
        assert not wrong, f"{module} imports {wrong}"
