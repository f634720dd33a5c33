"""The layer order of ``catgrasp_drake.layers`` holds for every import in the package (top level or in a function).

Also: every unit of the package is in the table (and every table entry exists),
and no module imports another module's private (``_``) names.
"""

from __future__ import annotations

import ast
from pathlib import Path

from catgrasp_drake.layers import LAYER_OF, LAYERS, PACKAGE, ROOT, unit_of

PACKAGE_DIR = Path(__file__).resolve().parents[2] / PACKAGE
REPO = PACKAGE_DIR.parent


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path):
    """``(line, imported module, imported names)`` of every import in ``path`` (relative ones resolved)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name, ()
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            yield node.lineno, target, tuple(a.name for a in node.names)


def _target_units(target: str, names: tuple[str, ...]) -> list[str]:
    """Units an import reaches: ``from catgrasp_drake import trial`` reaches ``trial``, not the root."""
    unit = unit_of(target)
    if unit is None:
        return []
    if unit == ROOT and names:
        return sorted({n if n in LAYER_OF else ROOT for n in names})
    return [unit]


def _layer(unit: str) -> str:
    i = LAYER_OF[unit]
    return f"layer {i} ({LAYERS[i][0]})"


def layer_violations(package_dir: Path = PACKAGE_DIR) -> list[str]:
    """Every import against the order, as "file:line: what (rule)"."""
    out = []
    for path in sorted(package_dir.rglob("*.py")):
        rel = path.relative_to(REPO).as_posix()
        module = _module_name(path)
        unit = unit_of(module)
        if unit not in LAYER_OF:
            out.append(f"{rel}:1: unit {unit!r} is not in catgrasp_drake.layers.LAYERS (add it to a layer)")
            continue
        for line, target, names in _imports(path):
            for other in _target_units(target, names):
                if other == unit:
                    continue
                if other not in LAYER_OF:
                    out.append(f"{rel}:{line}: imports {target}, whose unit {other!r} is not in the layer table")
                elif LAYER_OF[other] > LAYER_OF[unit]:
                    out.append(f"{rel}:{line}: {unit} ({_layer(unit)}) imports {target} ({_layer(other)}): "
                               "a module may import only its own unit and lower layers")
                elif LAYER_OF[other] == LAYER_OF[unit]:
                    out.append(f"{rel}:{line}: {unit} imports {target}, both in {_layer(unit)}: "
                               "the units of one layer are independent of each other")
    return out


def test_every_import_follows_the_layer_order():
    violations = layer_violations()
    assert not violations, "imports against catgrasp_drake.layers.LAYERS:\n" + "\n".join(violations)


def test_the_layer_table_names_what_exists():
    units = {unit_of(_module_name(p)) for p in PACKAGE_DIR.rglob("*.py")}
    table = [u for _, layer in LAYERS for u in layer]
    assert len(table) == len(set(table)), "a unit is in two layers"
    assert set(table) == units, \
        f"in the table only: {sorted(set(table) - units)}; missing: {sorted(units - set(table))}"


def test_the_checker_catches_a_wrong_import(tmp_path):
    """A core module importing the station (at module top or in a function) is reported with file, line and rule."""
    fake = tmp_path / PACKAGE / "core"
    fake.mkdir(parents=True)
    (fake.parent / "__init__.py").write_text("")
    (fake / "__init__.py").write_text("")
    (fake / "bad.py").write_text("import numpy\n\n\ndef f():\n    from catgrasp_drake.station import builder\n")
    global REPO
    saved, REPO = REPO, tmp_path
    try:
        found = layer_violations(tmp_path / PACKAGE)
    finally:
        REPO = saved
    assert len(found) == 1 and found[0].startswith(f"{PACKAGE}/core/bad.py:5: core (layer 1")
    assert "imports catgrasp_drake.station" in found[0] and "only its own unit and lower layers" in found[0]


def test_no_private_names_imported_across_modules():
    found = []
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        for line, target, names in _imports(path):
            if unit_of(target) is not None and target != _module_name(path):
                found += [f"{path.relative_to(REPO)}:{line}: {target}.{n}" for n in names if n.startswith("_")]
    assert not found, "private names imported from other modules:\n" + "\n".join(found)


def test_no_import_cycle_between_modules():
    """Not even inside one unit (the layer order covers the units), counting imports inside functions."""
    modules = {_module_name(p): p for p in PACKAGE_DIR.rglob("*.py")}
    graph = {m: set() for m in modules}
    for m, path in modules.items():
        for _, target, names in _imports(path):
            for t in [target] + [f"{target}.{n}" for n in names]:
                if t in modules and t != m:
                    graph[m].add(t)
    state, cycles = {}, []

    def visit(m, stack):
        state[m] = "open"
        for t in sorted(graph[m]):
            if state.get(t) == "open":
                cycles.append(" -> ".join(stack[stack.index(t):] + [t]))
            elif t not in state:
                visit(t, stack + [t])
        state[m] = "done"

    for m in sorted(modules):
        if m not in state:
            visit(m, [m])
    assert not cycles, "import cycles:\n" + "\n".join(cycles)
