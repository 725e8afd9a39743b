"""The import graph of the package and the agents points one way: no cycle, no edge upward.

Every import counts: at the top, inside functions, and under ``if TYPE_CHECKING``. The library
imports no study, agent or benchmark; agents and benchmarks import no study; importing the
library loads none of the optional extras' heavy packages.
"""

import ast
import graphlib
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _modules() -> dict[str, Path]:
    """Module name -> file, for agents/, benchmarks/, studies/ and dice_env/ (packages by name)."""
    files = [*ROOT.glob("agents/*.py"), *ROOT.glob("benchmarks/*.py"), *ROOT.glob("studies/*.py"),
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
    assert _imports(modules["dice_env.model.defaults"], "dice_env.model.defaults", modules) == {
        "dice_env.model.checks"}


def _top(module: str) -> str:
    return module.partition(".")[0]


def test_the_library_imports_no_study_agent_or_benchmark():
    modules = _modules()
    assert any(_top(m) == "studies" for m in modules)  # the studies are among those read
    for module, path in modules.items():
        if _top(module) == "dice_env":
            above = {m for m in _imports(path, module, modules)
                     if _top(m) in ("studies", "agents", "benchmarks")}
            assert not above, f"{module} imports {above}"


def test_agents_and_benchmarks_import_no_study():
    modules = _modules()
    for module, path in modules.items():
        if _top(module) in ("agents", "benchmarks"):
            studies = {m for m in _imports(path, module, modules) if _top(m) == "studies"}
            assert not studies, f"{module} imports {studies}"


# Packages of the optional extras that importing the library must not load. The SB3 adapter,
# dice_env.envs.sb3 (reached through dice_env.envs' lazy names), is Stable-Baselines3's by nature.
HEAVY = ("matplotlib", "tqdm", "scipy", "torch", "stable_baselines3")
ADAPTERS = ("dice_env.envs.sb3",)
IMPORT_ALL = f"""
import importlib, pkgutil, sys
import gymnasium, numba, numpy  # the core dependencies: what they load themselves is theirs
before = set(sys.modules)
import dice_env
for info in pkgutil.walk_packages(dice_env.__path__, prefix="dice_env."):
    if not info.name.endswith("__main__") and info.name not in {ADAPTERS!r}:
        importlib.import_module(info.name)
loaded = {{m.partition(".")[0] for m in set(sys.modules) - before}}
print(" ".join(sorted(loaded & set({HEAVY!r}))))
"""


def test_importing_the_library_loads_no_optional_heavy_package():
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", IMPORT_ALL], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600, check=True)
    assert done.stdout.split() == []


# The layers, bottom up: a module imports from its own layer and from those listed for it only
# (the package itself, ``dice_env``, stands for the names it exports: the model, the
# simulation and the envs).
LAYERS = {
    "dice_env.model": set(),
    "dice_env.physics": set(),
    "dice_env.intervals": set(),
    "dice_env.markdown": set(),
    "dice_env.provenance": set(),
    "dice_env.disk": set(),
    "dice_env.simulation": {"dice_env.model", "dice_env.physics", "dice_env.disk"},
    "dice_env.throws": {"dice_env.model", "dice_env.simulation", "dice_env.intervals"},
    # the chunked runner: the top of the simulation, its default draw the hand of the throws
    "dice_env.simulation.runner": {"dice_env.model", "dice_env.simulation", "dice_env.throws",
                                   "dice_env.disk"},
    # the env's hand holds its dice as the throws' hands do (dice_env.throws.layout)
    "dice_env.envs": {"dice_env.model", "dice_env.simulation", "dice_env.throws",
                      "dice_env.disk"},
    "dice_env.viewer": {"dice_env", "dice_env.model", "dice_env.simulation", "dice_env.envs",
                        "dice_env.disk"},
}


def _layer(module: str) -> str:
    """The longest name of :data:`LAYERS` that is ``module`` or a package above it."""
    return max((layer for layer in LAYERS if module == layer or module.startswith(layer + ".")),
               key=len, default=module)


def test_each_layer_imports_only_the_layers_below_it():
    modules = _modules()
    for module, path in modules.items():
        if _layer(module) not in LAYERS:
            continue
        allowed = LAYERS[_layer(module)] | {_layer(module)}
        wrong = {m for m in _imports(path, module, modules)
                 if m.startswith("dice_env") and _layer(m) not in allowed}
        assert not wrong, f"{module} imports {wrong}"


def test_the_benchmarks_that_import_the_agents_run_as_scripts_from_a_checkout():
    """``python benchmarks/NAME.py`` (benchmarks/ on the path, not the root) finds agents/."""
    scripts = [path for path in sorted(ROOT.glob("benchmarks/*.py"))
               if any(_top(m) == "agents" for m in _imports(path, f"benchmarks.{path.stem}",
                                                            _modules()))]
    assert scripts  # tasks.py and learn_from_scratch.py train or evaluate agents
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    for path in scripts:
        done = subprocess.run([sys.executable, str(path.relative_to(ROOT)), "--help"], cwd=ROOT,
                              env=env, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, f"{path.name}: {done.stderr[-400:]}"
