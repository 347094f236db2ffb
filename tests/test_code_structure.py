"""The package's structure: layers without cycles or upward imports (imports inside functions
counted), no private name across modules, citations that resolve, and the test suite's own
rules (derandomized property tests)."""

from __future__ import annotations

import ast
import os
import re
from pathlib import Path

import pytest
from hypothesis import settings

import stt_codegen

PACKAGE = Path(stt_codegen.__file__).parent
REPO = PACKAGE.parent


def _module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _target(module: str, node: ast.ImportFrom, is_package: bool) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or \
        (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports_of(path: Path, typing: bool = False) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement of a module, wherever it is: the module's body, function and
    method bodies, ``try`` blocks; the body of an ``if TYPE_CHECKING:`` (never run) only
    with ``typing``."""
    found: list[ast.Import | ast.ImportFrom] = []

    def visit(node: ast.AST) -> None:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            found.append(node)
        elif isinstance(node, ast.If) and _is_type_checking(node.test) and not typing:
            for child in node.orelse:
                visit(child)
            return
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(ast.parse(path.read_text()))
    return found


def import_graph(typing: bool = False) -> dict[str, set[str]]:
    """Module -> the package's modules it imports, at import time or in a function, parent
    packages included (importing ``a.b.c`` first imports ``a.b``); with ``typing`` also
    those imported for type annotations only (``if TYPE_CHECKING:``)."""
    graph: dict[str, set[str]] = {}
    for module, path in MODULES.items():
        edges: set[str] = set()
        for node in imports_of(path, typing):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                target = _target(module, node, path.name == "__init__.py")
                names = [f"{target}.{a.name}" if f"{target}.{a.name}" in MODULES else target
                         for a in node.names]
            edges |= {n for n in names if n in MODULES}
        for name in list(edges):
            parts = name.split(".")
            edges |= {".".join(parts[:k]) for k in range(2, len(parts))
                      if not module.startswith(".".join(parts[:k]) + ".")}
        edges.discard(module)
        graph[module] = edges
    return graph


def package_of(module: str) -> str:
    """``stt_codegen.design.search`` -> ``design``; the front door ``stt_codegen`` itself."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def package_graph() -> dict[str, set[str]]:
    """Package -> the other packages its modules import (:func:`import_graph`, by package)."""
    actual: dict[str, set[str]] = {package_of(m): set() for m in MODULES}
    for module, edges in import_graph().items():
        actual[package_of(module)] |= {package_of(e) for e in edges} - {package_of(module)}
    return actual


def stated_layers() -> list[tuple[str, set[str]]]:
    """docs/architecture.md's table "package | imports", in its order: (package, imports)."""
    doc = (REPO / "docs" / "architecture.md").read_text()
    table = doc[doc.index("| package | imports |"):].split("\n\n", 1)[0]
    rows = []
    for row in table.splitlines()[2:]:
        package, imports = row.strip("|").split("|")
        name = re.findall(r"`([\w.]+)`", package)[0]
        rows.append((name, set(re.findall(r"`([\w.]+)`", imports.split(";")[0]))))
    return rows


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of the graph as a list of modules (first == last), or None."""
    state: dict[str, int] = {}

    def visit(node: str, path: list[str]) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            if not state.get(nxt):
                cycle = visit(nxt, path)
                if cycle:
                    return cycle
        path.pop()
        state[node] = 2
        return None

    for start in sorted(graph):
        if not state.get(start):
            cycle = visit(start, [])
            if cycle:
                return cycle
    return None


def test_the_graph_sees_the_imports():
    graph = import_graph()
    assert len(graph) > 50
    assert "stt_codegen.spec.loader" in graph["stt_codegen.design.search"]
    assert "stt_codegen.codegen" in graph["stt_codegen.runtime.compiled"]   # parent package
    assert "stt_codegen.runtime.simulate" in graph["stt_codegen.cli.common"]  # in a function
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_imports_of_counts_functions_and_skips_type_checking(tmp_path):
    path = tmp_path / "m.py"
    path.write_text("import a\nfrom typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                    "    import hidden\nelse:\n    import shown\n"
                    "def f():\n    import inner\n    class C:\n        def g(self):\n"
                    "            from deep import x\n")
    names = [a.name for n in imports_of(path) for a in n.names]
    assert names == ["a", "TYPE_CHECKING", "shown", "inner", "x"]


def test_no_import_cycle_between_the_packages_modules():
    """Counting the imports inside functions too."""
    assert find_cycle(import_graph()) is None


def test_no_cycle_between_modules_through_type_annotations():
    """A module that names another's type only under ``if TYPE_CHECKING:`` still depends on
    it: ``design/result.py`` once imported ``design/cascade_gain.py`` in a function while
    ``cascade_gain`` took ``result.Design`` for its annotations. Between two modules of one
    package as between packages, a dependency goes one way."""
    assert find_cycle(import_graph(typing=True)) is None


def test_the_architecture_document_states_the_dependencies():
    """docs/architecture.md's table "package | imports" is the import graph, by package."""
    assert dict(stated_layers()) == package_graph()


def test_no_package_imports_a_package_below_it():
    """Layers: a package imports only the packages listed above it in the table (so the
    packages have no cycle either), counting the imports inside functions."""
    order = [name for name, _ in stated_layers()]
    assert sorted(order) == sorted(package_graph())
    upward = sorted(f"{package} imports {other}" for package, imports in package_graph().items()
                    for other in imports if order.index(other) > order.index(package))
    assert upward == []


def test_no_module_imports_a_private_name_from_another_module():
    """``from x import _y`` anywhere in the package (functions included) is refused."""
    offenders = []
    for module, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                for alias in node.names:
                    if alias.name.startswith("_") and not alias.name.startswith("__"):
                        offenders.append(f"{module}:{node.lineno} imports {alias.name}")
    assert offenders == []


def test_citations_of_the_decisions_resolve():
    """Code, tests, specs and documents cite docs/decisions.md by number ("docs/decisions.md,
    decision N"); every cited decision exists, and no citation of the lists that
    docs/decisions.md replaced (the README's *Decisions*, design notes items) is left."""
    decisions = (REPO / "docs" / "decisions.md").read_text()
    numbers = [int(m) for m in re.findall(r"^(\d+)\. \*\*", decisions, flags=re.M)]
    assert numbers == list(range(1, len(numbers) + 1)) and len(numbers) >= 17
    cited = [int(n) for n in re.findall(r"\bdecisions?\s+(\d+)", decisions)]   # its own
    files = [*PACKAGE.rglob("*.py"), *(REPO / "tests").glob("*.py"),
             *(REPO / "tests" / "specs").glob("*.toml"), *(REPO / "docs").glob("*.md"),
             REPO / "README.md"]
    for path in files:
        text = path.read_text()
        assert "paper-notes" not in text or path.name == Path(__file__).name, path
        if path.name != Path(__file__).name:
            stale = re.findall(r"design[- ]notes(?:\.md)?,? items? \d+|README,? \*?\"?Decisions"
                               r"|README's \*?\"?Decisions|README decision", text)
            assert stale == [], (path, stale)
        cited += [int(n) for n in re.findall(r"decisions(?:\.md)?\]?(?:\([^)]*\))?,?\s+"
                                             r"decisions?\s+(\d+)", text)]
    assert cited and set(cited) <= set(numbers)


def test_property_tests_are_derandomized_by_default():
    """conftest loads the 'ci' profile under CI, and by default."""
    if not os.environ.get("CI") and os.environ.get("HYPOTHESIS_PROFILE", "ci") != "ci":
        pytest.skip("another Hypothesis profile was asked for outside CI")
    assert settings.default.derandomize is True and settings.default.database is None


def test_every_package_is_installed():
    """pyproject.toml lists the packages explicitly: a new subpackage (``cli``,
    ``design.certificate``) missing from the list would be absent from a wheel."""
    import tomllib
    listed = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    folders = {_module_name(p) for p in PACKAGE.rglob("__init__.py")}
    assert folders <= listed


def _order_tests(tree: ast.AST) -> list[int]:
    """Lines where code decides on ``<x>.second_order`` itself: compared with ``None`` or
    used as a truth value (an ``if``, ``while``, conditional expression or boolean)."""
    def is_order(node: ast.expr) -> bool:
        return isinstance(node, ast.Attribute) and node.attr == "second_order"
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare) and any(
                is_order(side) for side in (node.left, *node.comparators)) and any(
                isinstance(side, ast.Constant) and side.value is None
                for side in (node.left, *node.comparators)):
            lines.append(node.lineno)
        tests = ([node.test] if isinstance(node, (ast.If, ast.While, ast.IfExp)) else
                 node.values if isinstance(node, ast.BoolOp) else
                 [node.operand] if isinstance(node, ast.UnaryOp)
                 and isinstance(node.op, ast.Not) else [])
        lines += [t.lineno for t in tests if is_order(t)]
    return sorted(lines)


def test_order_tests_are_found():
    tree = ast.parse("if spec.second_order is not None: pass\n"
                     "a = 1 if d.spec.second_order else 2\n"
                     "b = not s.second_order\n"
                     "c = s.second_order.model\n")
    assert _order_tests(tree) == [1, 2, 3]


def test_the_plant_order_is_decided_in_one_place():
    """The controller variant (law (13) or the cascade) follows ``Spec.order``, defined in
    ``spec/``: no module elsewhere tests ``second_order`` against ``None`` or for truth
    (it reads the second-order plant's fields only)."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.relative_to(PACKAGE).parts[0] == "spec":
            continue
        lines = _order_tests(ast.parse(path.read_text()))
        if lines:
            found[str(path.relative_to(PACKAGE))] = lines
    assert not found, f"test Spec.order instead of second_order: {found}"


def _model_name_comparisons(tree: ast.AST, names: frozenset[str]) -> list[int]:
    """Lines where code compares something with a plant-model name written as a string
    literal (``== "linear"``, ``in ("quadrotor", ...)``): behaviour per model is a lookup
    in a table keyed by the model, not a comparison."""
    def is_name(node: ast.expr) -> bool:
        if isinstance(node, ast.Constant):
            return node.value in names
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            return any(is_name(e) for e in node.elts)
        return False
    return sorted(node.lineno for node in ast.walk(tree) if isinstance(node, ast.Compare)
                  and any(is_name(side) for side in (node.left, *node.comparators)))


def test_model_name_comparisons_are_found():
    names = frozenset({"linear", "quadrotor"})
    tree = ast.parse("if model == 'linear': pass\n"
                     "b = spec.plant_model in ('x', 'quadrotor')\n"
                     "c = TABLE[model]\n"
                     "d = model != 'other'\n"
                     "e = 'quadrotor' != order.model\n")
    assert _model_name_comparisons(tree, names) == [1, 2, 5]


def test_no_module_compares_plant_model_names():
    """What a plant model does is looked up in the registry's tables (spec/plants.py
    holds the names; each behaviour a table keyed by them), so a new model without a
    behaviour is refused by name rather than handled as another model."""
    from stt_codegen.spec.plants import ALL_PLANT_MODELS
    names = frozenset(ALL_PLANT_MODELS)
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        lines = _model_name_comparisons(ast.parse(path.read_text()), names)
        if lines:
            found[str(path.relative_to(PACKAGE))] = lines
    assert not found, f"look the model up in a per-model table instead: {found}"


#: The module that decides the controller variant (docs/architecture.md, "Controller variants").
VARIANT_MODULE = PACKAGE / "spec" / "variants.py"
#: The classes of the variants' stages (``Design.stage``).
STAGE_CLASSES = frozenset({"LookAhead", "SecondStage"})


def _variant_branches(tree: ast.AST) -> list[int]:
    """Lines where code decides a controller variant itself rather than asking the variant
    object: ``<x>.order`` or ``<x>.variant`` compared with ``==``/``!=``, ``drive`` or
    ``stage`` (a name or an attribute) compared with ``None``, ``isinstance`` on a stage
    class."""
    def named(node: ast.expr, names: set[str]) -> bool:
        return (isinstance(node, ast.Name) and node.id in names) or \
            (isinstance(node, ast.Attribute) and node.attr in names)
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            sides = (node.left, *node.comparators)
            if any(isinstance(op, (ast.Eq, ast.NotEq)) for op in node.ops) and any(
                    isinstance(side, ast.Attribute) and side.attr in ("order", "variant")
                    for side in sides):
                lines.append(node.lineno)
            elif any(named(side, {"drive", "stage"}) for side in sides) and any(
                    isinstance(side, ast.Constant) and side.value is None for side in sides):
                lines.append(node.lineno)
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id == "isinstance" and len(node.args) == 2):
            kinds = node.args[1]
            kinds = kinds.elts if isinstance(kinds, ast.Tuple) else [kinds]
            if any(named(k, set(STAGE_CLASSES)) for k in kinds):
                lines.append(node.lineno)
    return sorted(lines)


def test_variant_branches_are_found():
    tree = ast.parse("if spec.order == 2: pass\n"
                     "a = plant_entry(m).order != 1\n"
                     "b = 1 if design.spec.variant == 'cascade' else 2\n"
                     "c = spec.drive is None\n"
                     "d = stage is not None\n"
                     "e = isinstance(stage, LookAhead)\n"
                     "f = isinstance(s, (int, stage_module.SecondStage))\n"
                     "g = spec.task_order == 'any'\n"
                     "h = variant == free\n"
                     "i = spec.order + 1\n"
                     "j = x is None\n")
    assert _variant_branches(tree) == [1, 2, 3, 4, 5, 6, 7]


def variant_branches(package: Path) -> dict[str, list[int]]:
    """Every variant branch of a package's tree (:func:`_variant_branches`) outside its
    variant module, by file."""
    found = {}
    for path in sorted(package.rglob("*.py")):
        if path.relative_to(package) == VARIANT_MODULE.relative_to(PACKAGE):
            continue
        lines = _variant_branches(ast.parse(path.read_text()))
        if lines:
            found[str(path.relative_to(package))] = lines
    return found


def test_the_controller_variant_is_decided_in_one_place():
    """What differs between law (13), the cascade and the look-ahead law is a role of the
    variant object (``spec/variants.py``): nowhere else does the package compare
    ``order`` or ``variant``, test ``drive`` or ``stage`` against ``None`` or ask
    ``isinstance`` of a stage class."""
    found = variant_branches(PACKAGE)
    assert not found, f"ask the ControllerVariant (spec/variants.py) instead: {found}"


def _role_calls(tree: ast.AST) -> list[tuple[int, str | None]]:
    """``(line, role)`` of each ``<variant>.entry(role)`` call (``None``: the role is not a
    string literal) and of each ``variant_of_stage(...)`` call (role ``stage_class``)."""
    calls = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        if isinstance(func, ast.Attribute) and func.attr == "entry":
            arg = node.args[0] if len(node.args) == 1 and not node.keywords else None
            calls.append((node.lineno, arg.value if isinstance(arg, ast.Constant)
                          and isinstance(arg.value, str) else None))
        elif isinstance(func, ast.Name) and func.id == "variant_of_stage":
            calls.append((node.lineno, "stage_class"))
    return calls


def test_every_role_of_every_variant_resolves():
    """Each variant fills every role of ``ROLES`` with a reference to a callable (a
    function, or a class for ``stage_class``) that exists."""
    from stt_codegen.spec.plants import VARIANTS
    from stt_codegen.spec.variants import CONTROLLER_VARIANTS, ROLES
    assert tuple(CONTROLLER_VARIANTS) == VARIANTS
    for name, variant in CONTROLLER_VARIANTS.items():
        assert variant.name == name and set(variant.roles) == set(ROLES)
        for role in ROLES:
            assert callable(variant.entry(role)), (name, role)


def test_a_layer_resolves_only_roles_of_its_own_or_upper_layers():
    """The variant module names behaviour in every layer by a dotted reference, resolved
    on first use: a module may resolve a role only if every variant's function for it is
    in the module's own package or one above it (the import rule of
    :func:`test_no_package_imports_a_package_below_it`, applied to what is resolved)."""
    from stt_codegen.spec.variants import CONTROLLER_VARIANTS
    order = [name for name, _ in stated_layers()]
    targets = {role: {package_of(ref.split(":")[0]) for v in CONTROLLER_VARIANTS.values()
                      for r, ref in v.roles.items() if r == role
                      and ref.startswith("stt_codegen.")}
               for role in next(iter(CONTROLLER_VARIANTS.values())).roles}
    offenders, seen = [], set()
    for module, path in MODULES.items():
        if path == VARIANT_MODULE:
            continue
        for line, role in _role_calls(ast.parse(path.read_text())):
            if role not in targets:
                offenders.append(f"{module}:{line} resolves {role!r}, not a literal role")
                continue
            seen.add(role)
            below = [t for t in targets[role]
                     if order.index(t) > order.index(package_of(module))]
            if below:
                offenders.append(f"{module}:{line} resolves {role!r} into {below}")
    assert offenders == []
    # the deployed and oracle steps are for the variants' equivalence tests
    # (tests/test_variants.py); every other role has a caller in the package
    unused = set(targets) - seen - {"casadi_step", "oracle_step"}
    assert not unused, f"roles no module uses: {unused}"
