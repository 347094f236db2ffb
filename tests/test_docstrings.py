"""The public surface a newcomer reads is documented in full, with examples that run; every
other name has at least a one-line docstring (in the manner of python-control's
``control/tests/docstrings_test.py``).

The public surface (:data:`PUBLIC_SURFACE`) is the front door, ``stt_codegen.__all__``, and
the documented extension points (:data:`EXTENSION_POINTS`). Every other name in a module's
``__all__`` is internal: ``__all__`` is the list of names other modules of the package may
import, not a promise to users (docs/architecture.md, "Public and internal names").

Rules, checked per module with numpydoc's own parser:

- ``__all__`` is a list of distinct strings, each defined in the module, and it names every
  name that another module of the package imports from this one (``test_code_structure.py``
  forbids private names across modules).
- A function or class of the public surface has a numpydoc docstring with an ``Examples``
  section, run as a doctest (:func:`test_examples_run`, in a process and a scratch folder of
  their own; bundled cases only, nothing slow). A function's ``Parameters`` section names every parameter
  (``self``/``cls`` excluded, ``*args``/``**kwargs`` as such) and no parameter that does not
  exist; unless it is annotated to return ``None`` it has a ``Returns`` (or ``Yields``)
  section. A class's docstring covers its constructor's arguments: ``Parameters`` for a
  class with its own ``__init__``; for a data class (dataclass, NamedTuple, pydantic model),
  whose constructor arguments are its fields, ``Attributes`` (the project's style for
  records) or ``Parameters``; a pydantic field with a ``description`` is documented by it
  (the JSON schema's one source). A constructor inherited from outside the package
  (``Exception``, ``object``) and enumerations have nothing to document.
- An internal function or class (one in ``__all__``, defined in the module) has a docstring
  whose first line says what it is; the sections are optional, but a ``Parameters`` section
  that is there names every parameter and no other (a stale one is worse than none).

Methods are not checked. The test ids are the module names, so ``-k stt_codegen.spec`` runs
one package.
"""

from __future__ import annotations

import ast
import dataclasses
import enum
import functools
import importlib
import inspect
import pkgutil
import subprocess
import sys
import textwrap
import typing
import warnings
from pathlib import Path

import pytest
from numpydoc.docscrape import NumpyDocString
from pydantic import BaseModel

import stt_codegen

PACKAGE = "stt_codegen"
PACKAGE_DIR = Path(stt_codegen.__file__).parent


def _module_names() -> list[str]:
    names = [PACKAGE]
    for info in pkgutil.walk_packages(stt_codegen.__path__, prefix=f"{PACKAGE}."):
        # ``__main__`` runs the CLI when imported; templates hold no Python API.
        if info.name.endswith(".__main__") or info.name.startswith(f"{PACKAGE}.templates"):
            continue
        names.append(info.name)
    return sorted(names)


MODULES = _module_names()

#: The documented extension points, ``"module:name"``, beside the front door: the spec and
#: the design (also front-door names), the backend registry, the code printer of
#: ``codegen/emit/``. The variant registry joins this list when it exists.
EXTENSION_POINTS = [
    "stt_codegen.spec.loader:Spec",
    "stt_codegen.design.result:Design",
    "stt_codegen.runtime.backends:register_backend",
    "stt_codegen.runtime.backends:make_controller",
    "stt_codegen.runtime.backends:backend_names",
    "stt_codegen.codegen.emit.printer:InstructionPrinter",
    "stt_codegen.spec.variants:ControllerVariant",
    "stt_codegen.spec.variants:variant_of",
]


def _public_surface() -> set[tuple[str, str]]:
    """``(module, name)`` of the front door's names (where they are defined) and of
    :data:`EXTENSION_POINTS`."""
    surface = set()
    for name in stt_codegen.__all__:
        obj = getattr(stt_codegen, name)
        if callable(obj):
            surface.add((obj.__module__, name))
    for point in EXTENSION_POINTS:
        module, name = point.split(":")
        surface.add((module, name))
    return surface


#: The public surface: every function and class a newcomer is shown (module notes).
PUBLIC_SURFACE = sorted(_public_surface())


def _module_path(name: str) -> Path:
    module = importlib.import_module(name)
    return Path(module.__file__)


def _imported_names() -> dict[str, set[str]]:
    """Module -> the names other modules of the package import from it by name."""
    modules = set(MODULES)
    used: dict[str, set[str]] = {}
    for importer in MODULES:
        path = _module_path(importer)
        is_package = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = importer.split(".") if is_package else importer.split(".")[:-1]
                base = base[:len(base) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            if source not in modules or source == importer:
                continue
            for alias in node.names:
                if alias.name != "*" and f"{source}.{alias.name}" not in modules:
                    used.setdefault(source, set()).add(alias.name)
    return used


@functools.cache
def _imported_names_cached() -> dict[str, set[str]]:
    return _imported_names()


def _public_objects(module_name: str) -> list[tuple[str, object]]:
    """The functions and classes of ``__all__`` defined in the module itself."""
    module = importlib.import_module(module_name)
    found = []
    for name in getattr(module, "__all__", []):
        obj = getattr(module, name, None)
        target = inspect.unwrap(obj) if callable(obj) else obj
        if not (inspect.isfunction(target) or inspect.isclass(obj)):
            continue
        if getattr(obj, "__module__", None) != module_name:
            continue
        found.append((name, obj))
    return found


def _parse(doc: str) -> NumpyDocString:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an unknown or misspelt section header is a failure
        return NumpyDocString(doc)


def _documented(section: list) -> set[str]:
    names: set[str] = set()
    for entry in section:
        for name in entry.name.split(","):
            names.add(name.strip())
    return names


def _parameter_names(signature: inspect.Signature) -> list[str]:
    names = []
    for parameter in signature.parameters.values():
        if parameter.name in ("self", "cls"):
            continue
        if parameter.kind is inspect.Parameter.VAR_POSITIONAL:
            names.append(f"*{parameter.name}")
        elif parameter.kind is inspect.Parameter.VAR_KEYWORD:
            names.append(f"**{parameter.name}")
        else:
            names.append(parameter.name)
    return names


def _matches(names: list[str], documented: set[str]) -> tuple[list[str], list[str]]:
    """(parameters not documented, documented names that are no parameter)."""
    bare = {n.lstrip("*"): n for n in names}
    missing = [n for n in names if n not in documented and n.lstrip("*") not in documented]
    extra = sorted(d for d in documented if d.lstrip("*") not in bare)
    return missing, extra


def _returns_value(function) -> bool:
    """Whether a function returns something other than None: from its return annotation, or,
    without one, from a ``return <value>`` or ``yield`` in its own body."""
    annotation = inspect.signature(function, eval_str=False).return_annotation
    if annotation is not inspect.Signature.empty:
        text = annotation if isinstance(annotation, str) else getattr(
            annotation, "__name__", repr(annotation))
        return text not in ("None", "NoneType", "NoReturn", "Never", "typing.NoReturn")
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(function)))
    except (OSError, TypeError, SyntaxError):
        return False
    body = tree.body[0]

    def visit(node: ast.AST) -> bool:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda,
                                  ast.ClassDef)):
                continue
            if isinstance(child, ast.Return) and child.value is not None and not (
                    isinstance(child.value, ast.Constant) and child.value.value is None):
                return True
            if isinstance(child, (ast.Yield, ast.YieldFrom)) or visit(child):
                return True
        return False

    return visit(body)


def _first_line(name: str, doc: str | None) -> list[str]:
    """The problem of a docstring without a first line saying what the name is."""
    if not doc or not doc.strip().splitlines()[0].strip():
        return [f"{name}: no docstring"]
    return []


def _examples(name: str, parsed: NumpyDocString) -> list[str]:
    if not any(">>>" in line for line in parsed["Examples"]):
        return [f"{name}: public, but no Examples section with a doctest (>>>)"]
    return []


def _function_problems(name: str, function, public: bool = True) -> list[str]:
    target = inspect.unwrap(function)
    doc = inspect.getdoc(target)
    if _first_line(name, doc):
        return _first_line(name, doc)
    try:
        parsed = _parse(doc)
    except (UserWarning, ValueError) as error:
        return [f"{name}: numpydoc cannot parse the docstring: {error}"]
    problems = []
    names = _parameter_names(inspect.signature(target, eval_str=False))
    missing, extra = _matches(names, _documented(parsed["Parameters"]))
    if missing and (public or parsed["Parameters"]):
        problems.append(f"{name}: Parameters does not document {missing}")
    if extra:
        problems.append(f"{name}: Parameters documents {extra}, which are no parameters")
    if not public:
        return problems
    if _returns_value(target) and not (parsed["Returns"] or parsed["Yields"]):
        problems.append(f"{name}: returns a value but has no Returns (or Yields) section")
    return problems + _examples(name, parsed)


def _is_data_class(cls: type) -> bool:
    return dataclasses.is_dataclass(cls) or issubclass(cls, BaseModel) or (
        issubclass(cls, tuple) and hasattr(cls, "_fields"))


def _data_fields(cls: type) -> tuple[list[str], set[str]]:
    """(the constructor's fields, the fields a pydantic ``description`` documents)."""
    if dataclasses.is_dataclass(cls):
        return [f.name for f in dataclasses.fields(cls) if f.init], set()
    if issubclass(cls, BaseModel):
        fields = cls.model_fields
        return list(fields), {n for n, f in fields.items() if f.description}
    return list(cls._fields), set()


def _own_constructor(cls: type) -> bool:
    """Whether the constructor comes from the package (not ``object``, ``Exception``, ...)."""
    for base in cls.__mro__:
        if "__init__" in vars(base) or "__new__" in vars(base):
            return base.__module__.split(".")[0] == PACKAGE
    return False


def _class_problems(name: str, cls: type, public: bool = True) -> list[str]:
    doc = inspect.getdoc(cls) if cls.__doc__ else None
    if _first_line(name, doc):
        return _first_line(name, doc)
    try:
        parsed = _parse(doc)
    except (UserWarning, ValueError) as error:
        return [f"{name}: numpydoc cannot parse the docstring: {error}"]
    if not public:
        return []
    if issubclass(cls, enum.Enum) or getattr(cls, "_is_protocol", False):
        return _examples(name, parsed)
    parameters = _documented(parsed["Parameters"])
    if _is_data_class(cls):
        fields, described = _data_fields(cls)
        documented = parameters | _documented(parsed["Attributes"]) | described
        missing = [f for f in fields if f not in documented]
        extra = sorted(parameters - set(fields))
        section = "Attributes (or Parameters)"
    elif _own_constructor(cls):
        names = _parameter_names(inspect.signature(cls, eval_str=False))
        missing, extra = _matches(names, parameters)
        section = "Parameters"
    else:
        return _examples(name, parsed)
    problems = []
    if missing:
        problems.append(f"{name}: {section} does not document the constructor's {missing}")
    if extra:
        problems.append(f"{name}: Parameters documents {extra}, which are no arguments")
    return problems + _examples(name, parsed)


@pytest.mark.parametrize("module_name", MODULES)
def test_module_declares_all(module_name: str) -> None:
    module = importlib.import_module(module_name)
    assert hasattr(module, "__all__"), f"{module_name} declares no __all__"
    names = module.__all__
    assert isinstance(names, list) and all(isinstance(n, str) for n in names), \
        f"{module_name}.__all__ is not a list of str"
    duplicates = sorted({n for n in names if names.count(n) > 1})
    assert not duplicates, f"{module_name}.__all__ repeats {duplicates}"
    undefined = [n for n in names if not hasattr(module, n)]
    assert not undefined, f"{module_name}.__all__ names {undefined}, not defined there"
    private = [n for n in names if n.startswith("_") and not n.startswith("__")]
    assert not private, f"{module_name}.__all__ names the private {private}"
    undeclared = sorted(_imported_names_cached().get(module_name, set()) - set(names))
    assert not undeclared, \
        f"other modules import {undeclared} from {module_name}, but its __all__ omits them"


@pytest.mark.parametrize("module_name", MODULES)
def test_docstrings(module_name: str) -> None:
    problems = []
    for name, obj in _public_objects(module_name):
        public = (module_name, name) in PUBLIC_SURFACE
        if inspect.isclass(obj):
            problems += _class_problems(name, obj, public)
        else:
            problems += _function_problems(name, obj, public)
    assert not problems, f"{module_name}:\n  " + "\n  ".join(problems)


def test_the_public_surface_is_defined_where_listed():
    """Each entry names a function or class its module defines and lists in ``__all__``."""
    for module_name, name in PUBLIC_SURFACE:
        module = importlib.import_module(module_name)
        assert name in module.__all__, (module_name, name)
        assert (name, getattr(module, name)) in _public_objects(module_name), (module_name, name)


#: Runs the ``Examples`` of ``module:name`` arguments as doctests; prints the failures and
#: the names without an example; exits 1 if any.
_RUN_EXAMPLES = """
import doctest, importlib, sys
runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
finder = doctest.DocTestFinder(recurse=False)
missing = []
for entry in sys.argv[1:]:
    module_name, name = entry.split(":")
    obj = getattr(importlib.import_module(module_name), name)
    tests = [t for t in finder.find(obj, entry, globs={}) if t.examples]
    missing += [] if tests else [entry]
    for test in tests:
        runner.run(test)
print("without examples:", missing)
sys.exit(1 if runner.summarize(verbose=False).failed or missing else 0)
"""


@pytest.mark.slow
def test_examples_run(tmp_path):
    """The ``Examples`` of every public name run as doctests, in one process of their own
    (an example may register a backend or write a file) in a scratch folder."""
    entries = [f"{module}:{name}" for module, name in PUBLIC_SURFACE]
    done = subprocess.run([sys.executable, "-c", _RUN_EXAMPLES, *entries], cwd=tmp_path,
                          capture_output=True, text=True, timeout=1800)
    assert done.returncode == 0, done.stdout[-8000:] + done.stderr[-2000:]


# The checker itself: each rule catches what it should.

def _sample(a: int, b: float = 1.0, *args: int, **kwargs: int) -> float:
    """Sum.

    Parameters
    ----------
    a : int
        First.
    b : float
        Second.
    *args, **kwargs : int
        More.

    Returns
    -------
    float
        The sum.
    """
    return a + b


def _undocumented(a: int, c: int) -> None:
    """No sections.

    Parameters
    ----------
    a : int
        First.
    ghost : int
        Not a parameter.
    """


def _no_returns(a: int) -> int:
    """Returns a value without saying so.

    Parameters
    ----------
    a : int
        First.
    """
    return a


def _unannotated(a):
    """Returns a value, no annotation.

    Parameters
    ----------
    a : int
        First.
    """
    return a


@dataclasses.dataclass
class _Record:
    """A record.

    Attributes
    ----------
    x : float
        Documented.
    """

    x: float
    y: float


class _WithInit:
    """A class.

    Parameters
    ----------
    p : int
        Documented.
    """

    def __init__(self, p: int, q: int) -> None:
        self.p, self.q = p, q


class _Plain(Exception):
    """An error with the inherited constructor."""


def _sample_with_example(a: int) -> int:
    """Twice ``a``.

    Parameters
    ----------
    a : int
        First.

    Returns
    -------
    int
        ``2 a``.

    Examples
    --------
    >>> _sample_with_example(2)
    4
    """
    return 2 * a


def _internal(a: int) -> int:
    """Twice ``a`` (internal: one line is enough)."""
    return 2 * a


def _no_docstring(a: int) -> int:
    return 2 * a


def test_the_checker_accepts_a_complete_docstring():
    assert _function_problems("_sample_with_example", _sample_with_example) == []
    assert _function_problems("_sample", _sample, public=False) == []


def test_the_checker_requires_examples_of_a_public_name_only():
    assert any("Examples" in p for p in _function_problems("_sample", _sample))
    assert any("Examples" in p for p in _class_problems("_Plain", _Plain))
    assert _function_problems("_internal", _internal, public=False) == []
    assert _class_problems("_Plain", _Plain, public=False) == []


def test_the_checker_requires_a_docstring_of_an_internal_name():
    assert _function_problems("_no_docstring", _no_docstring, public=False) == \
        ["_no_docstring: no docstring"]
    assert _function_problems("_no_docstring", _no_docstring) == ["_no_docstring: no docstring"]


def test_the_checker_finds_a_stale_parameters_section_of_an_internal_name():
    problems = _function_problems("_undocumented", _undocumented, public=False)
    assert any("['c']" in p for p in problems) and any("ghost" in p for p in problems)


def test_the_checker_finds_missing_and_extra_parameters():
    problems = _function_problems("_undocumented", _undocumented)
    assert any("['c']" in p for p in problems)
    assert any("ghost" in p for p in problems)
    assert not any("Returns" in p for p in problems)  # annotated -> None


def test_the_checker_requires_returns():
    assert any("Returns" in p for p in _function_problems("_no_returns", _no_returns))
    assert any("Returns" in p for p in _function_problems("_unannotated", _unannotated))


def test_the_checker_covers_constructors(monkeypatch):
    monkeypatch.setattr(_WithInit, "__module__", f"{PACKAGE}.sample")
    assert any("['y']" in p for p in _class_problems("_Record", _Record))
    assert any("['q']" in p for p in _class_problems("_WithInit", _WithInit))
    assert _class_problems("_Plain", _Plain) == ["_Plain: public, but no Examples section with a doctest (>>>)"]


def test_the_checker_refuses_an_unknown_section():
    def misspelt(a: int) -> None:
        """Text.

        Paramaters
        ----------
        a : int
            First.
        """

    assert any("cannot parse" in p for p in _function_problems("misspelt", misspelt))
