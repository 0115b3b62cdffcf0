"""No import circles in sensfw (issue 26): no module imports one that imports it back,
directly or through others, lazily (inside a function) or not, ``if TYPE_CHECKING:`` imports
included (a reader still has to follow them).

The graph is read from the source with ``ast``: module A depends on module B when A imports
B or a name from B, and on every package above B, whose ``__init__`` runs first (so a
package depends on the submodules its ``__init__`` imports, and a module that imports
``sensfw.models.places`` depends on every shipped model ``sensfw.models`` registers). A
module's own packages are not its dependencies: they are being imported when it runs.
This is stricter than ``../shared/tools/import-circles``, which ignores what a package's
``__init__`` imports: effects importing ``sensfw.models.places`` while the shipped models
imported ``sensfw.effects`` was a circle it did not see.
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]



def modules(package: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every module of ``package`` (a folder)."""
    out = {}
    for f in sorted(package.rglob("*.py")):
        parts = list(f.relative_to(package.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = f
    return out


def imported(name: str, path: Path, node: ast.Import | ast.ImportFrom) -> list[str]:
    """Candidate dotted names an import statement of module ``name`` refers to."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    base = name.split(".")
    if path.name != "__init__.py":
        base = base[:-1]  # relative imports start at the module's package
    if node.level:
        base = base[:len(base) - (node.level - 1)]
        stem = ".".join(base + ([node.module] if node.module else []))
    else:
        stem = node.module or ""
    return [stem, *(f"{stem}.{a.name}" for a in node.names)]


def graph(package: Path) -> dict[str, dict[str, int]]:
    """Module -> {module it depends on: line of the first import}."""
    mods = modules(package)
    edges: dict[str, dict[str, int]] = {m: {} for m in mods}
    for m, f in mods.items():
        for node in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            if not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            for target in imported(m, f, node):
                while target and target not in mods:
                    target = target.rpartition(".")[0]
                parts = target.split(".") if target else []
                for k in range(1, len(parts) + 1):  # the target and the packages above it
                    dep = ".".join(parts[:k])
                    if dep in mods and dep != m and not m.startswith(dep + "."):
                        edges[m].setdefault(dep, node.lineno)
    return edges


def circles(edges: dict[str, dict[str, int]]) -> list[list[str]]:
    """The groups of two or more modules that reach each other (strongly connected)."""

    def reach(start):
        seen, todo = set(), [start]
        while todo:
            for nxt in edges[todo.pop()]:
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return seen

    reaches = {m: reach(m) for m in edges}
    groups = {frozenset({m} | {n for n in reaches[m] if m in reaches[n]}) for m in edges
              if m in reaches[m]}
    return sorted(sorted(g) for g in groups if len(g) > 1)


def describe(edges, group) -> str:
    lines = [" <-> ".join(group)]
    for a in group:
        lines += [f"  {a} line {line} imports {b}" for b, line in edges[a].items() if b in group]
    return "\n".join(lines)


def test_the_finder_sees_circles_through_lazy_imports_and_packages(tmp_path):
    """The check itself, on a package shaped like sensfw's models and effects before issue
    26: a model imports the effects inside a function, the effects' package imports its
    modules, one of which imports a module of the models' package, whose ``__init__``
    imports the model. Without the lazy import there is no circle."""
    pkg = tmp_path / "pkg"
    for folder in ("models", "effects"):
        (pkg / folder).mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "models" / "__init__.py").write_text("from . import shaft\n")
    (pkg / "models" / "places.py").write_text("class Place: ...\n")
    lazy = "def make(spec):\n    from ..effects import make_effect\n    return make_effect(spec)\n"
    (pkg / "models" / "shaft.py").write_text("from .places import Place\n" + lazy)
    (pkg / "effects" / "__init__.py").write_text("from .contact import make_effect\n")
    (pkg / "effects" / "contact.py").write_text(
        "from ..models.places import Place\n\ndef make_effect(spec):\n    return spec\n")
    assert circles(graph(pkg)) == [["pkg.effects", "pkg.effects.contact", "pkg.models",
                                    "pkg.models.shaft"]]
    (pkg / "models" / "shaft.py").write_text("from .places import Place\n")
    assert circles(graph(pkg)) == []


def test_no_import_circles():
    edges = graph(ROOT / "sensfw")
    assert len(edges) > 100  # every module was read
    found = circles(edges)
    assert not found, "\n".join(describe(edges, g) for g in found)
