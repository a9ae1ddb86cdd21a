"""The house's rules, read from the source (ast): imports point down the layers, no cycles, no private name
taken from another module, no module over 600 lines."""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "skfem_flex"
#: the layers from the bottom; a module may import its own layer and the ones below
LAYERS = ["errors", "numerics", "fem", "bodies", "elements", "scene", "scene_initial", "compiled", "schemes", "io",
          "analysis", "run", "scenes", "apps"]
MAX_LINES = 600


def _modules():
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(["skfem_flex"] + parts)] = path
    return out


MODULES = _modules()


def _layer(module):
    parts = module.split(".")
    if len(parts) < 2:
        return None                         # the package itself (its __init__ gathers the public names)
    return LAYERS.index(parts[1]) if parts[1] in LAYERS else None


def _imports(module, path):
    """(imported module, names, line) of every import of the package's own modules."""
    tree = ast.parse(path.read_text())
    is_pkg = path.name == "__init__.py"
    base = module.split(".") if is_pkg else module.split(".")[:-1]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                target = base[:len(base) - node.level + 1] + (node.module.split(".") if node.module else [])
                target = ".".join(target)
            else:
                target = node.module or ""
            if not target.startswith("skfem_flex"):
                continue
            names = [a.name for a in node.names]
            # "from pkg import module" imports the module
            mods = [f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES]
            out += [(m, [], node.lineno) for m in mods]
            rest = [n for n in names if f"{target}.{n}" not in MODULES]
            if rest:
                out.append((target, rest, node.lineno))
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("skfem_flex"):
                    out.append((a.name, [], node.lineno))
    return out


def test_imports_point_down_the_layers():
    wrong = []
    for module, path in MODULES.items():
        own = _layer(module)
        if own is None:
            continue
        for target, _, line in _imports(module, path):
            other = _layer(target)
            if other is not None and other > own:
                wrong.append(f"{module}:{line} imports {target} ({LAYERS[other]} is above {LAYERS[own]})")
    assert not wrong, "\n".join(wrong)


def test_no_import_cycles():
    graph = {m: {t for t, _, _ in _imports(m, p) if t in MODULES and t != m} for m, p in MODULES.items()}
    # a package's __init__ importing its own modules is how it exports names, not a cycle of ideas
    for m in graph:
        graph[m] = {t for t in graph[m] if not (MODULES[m].name == "__init__.py" and t.startswith(m + "."))}
    seen, stack, cycles = {}, [], []

    def visit(m):
        seen[m] = 1
        stack.append(m)
        for t in graph[m]:
            if seen.get(t) == 1:
                cycles.append(" → ".join(stack[stack.index(t):] + [t]))
            elif t not in seen:
                visit(t)
        stack.pop()
        seen[m] = 2
    for m in graph:
        if m not in seen:
            visit(m)
    assert not cycles, "\n".join(cycles)


def test_no_private_name_from_another_module():
    wrong = []
    for module, path in MODULES.items():
        for target, names, line in _imports(module, path):
            private = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if private and target != module:
                wrong.append(f"{module}:{line} imports {private} from {target}")
    assert not wrong, "\n".join(wrong)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_modules_are_at_most_600_lines(module):
    n = len(MODULES[module].read_text().splitlines())
    assert n <= MAX_LINES, f"{module} has {n} lines (at most {MAX_LINES}: split it by idea)"
