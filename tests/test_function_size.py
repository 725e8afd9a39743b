"""Functions stay readable: at most 120 lines and 10 parameters, the compiled loops excepted.

The numba kernels (``@njit``, ``@cuda.jit``) take scalars rather than groups and run one loop
each, on purpose (docs/performance.md); every other function of ``dice_env/``, ``agents/`` and
``studies/`` is held to the limits.
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MAX_LINES, MAX_PARAMETERS = 120, 10


def _compiled(node: ast.FunctionDef) -> bool:
    """Whether ``node`` is decorated by numba (``njit``, ``cuda.jit`` and the like)."""
    for decorator in node.decorator_list:
        target = decorator.func if isinstance(decorator, ast.Call) else decorator
        if "jit" in ast.unparse(target):
            return True
    return False


def _functions() -> list[tuple[str, ast.FunctionDef]]:
    """(where, node) of every function in dice_env/, agents/ and studies/."""
    found = []
    for path in sorted([*ROOT.glob("dice_env/**/*.py"), *ROOT.glob("agents/**/*.py"),
                          *ROOT.glob("studies/*.py")]):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                found.append((f"{path.relative_to(ROOT)}:{node.lineno} {node.name}", node))
    return found


def _parameters(node: ast.FunctionDef) -> int:
    """Parameters of ``node``, ``self``/``cls`` and ``*``/``**`` catch-alls included."""
    args = node.args
    names = [*args.posonlyargs, *args.args, *args.kwonlyargs]
    count = len(names) + bool(args.vararg) + bool(args.kwarg)
    return count - bool(names and names[0].arg in ("self", "cls"))


def test_the_walk_sees_the_kernels_and_the_drivers():
    names = {where.rsplit(" ", 1)[1]: _compiled(node) for where, node in _functions()}
    assert names["advance_group"] and names["die_move"]
    assert not names["simulate"] and not names["simulate_group"]


def test_no_long_function_outside_the_compiled_loops():
    long = [f"{where}: {node.end_lineno - node.lineno + 1} lines"
            for where, node in _functions()
            if not _compiled(node) and node.end_lineno - node.lineno + 1 > MAX_LINES]
    assert not long, long


def test_no_long_parameter_list_outside_the_compiled_loops():
    wide = [f"{where}: {_parameters(node)} parameters" for where, node in _functions()
            if not _compiled(node) and _parameters(node) > MAX_PARAMETERS]
    assert not wide, wide
