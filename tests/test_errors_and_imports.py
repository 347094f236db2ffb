"""Error kinds and exit codes; imports on demand; no global state changed by an import."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import design_of
import stt_codegen
from stt_codegen import cli
from stt_codegen.cli import cases as cases_command
from stt_codegen.codegen.errors import CodegenError
from stt_codegen.codegen.emit.errors import EmitError
from stt_codegen.embedded.target import BuildError
from stt_codegen.embedded.toolchain import MissingTool
from stt_codegen.errors import DesignError, SpecError, SttError, ToolchainError

PACKAGE = Path(stt_codegen.__file__).parent


def test_every_error_class_is_one_of_the_three_kinds():
    for kind in (CodegenError, EmitError, BuildError, MissingTool):
        assert issubclass(kind, ToolchainError)
    assert not issubclass(ToolchainError, (SpecError, DesignError))
    assert not issubclass(DesignError, SpecError) and not issubclass(SpecError, DesignError)
    codes = {kind: cli.exit_code(kind("x", "y") if kind is SpecError else kind("x"))
             for kind in (SpecError, DesignError, ToolchainError, CodegenError, SttError)}
    assert codes == {SpecError: 2, DesignError: 1, ToolchainError: 3, CodegenError: 3,
                     SttError: 3}
    assert cli.exit_code(MissingTool("qemu-system-arm", "qemu-system-arm")) == 3


@pytest.mark.parametrize("error, code", [
    (SpecError("prescribed_time", "must be positive"), 2),
    (DesignError("no tube avoids obstacle 1"), 1),
    (CodegenError("no C compiler found (set CC)"), 3),
    (BuildError(["arm-none-eabi-gcc"], "ld: cannot find -lm"), 3),
])
def test_main_maps_each_kind_to_its_exit_code(monkeypatch, capsys, error, code):
    def fail(args):
        raise error
    monkeypatch.setattr(cases_command, "cmd_cases", fail)
    assert cli.main(["cases"]) == code
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "Traceback" not in err
    assert err.count("\n") == 1 or isinstance(error, BuildError)   # + the tool's output


def test_a_library_parameter_is_reported_as_the_flag_the_user_knows(capsys):
    """``simulate(horizon=...)`` raises ``SpecError("horizon", ...)``; the CLI says ``--horizon``."""
    from stt_codegen.runtime.simulate import simulate
    with pytest.raises(SpecError) as info:
        simulate(design_of("omnirobot-s1"), horizon=-1.0)
    assert info.value.field == "horizon"
    assert cli.main(["simulate", "omnirobot-s1", "--horizon", "-1"]) == 2
    assert capsys.readouterr().err.startswith("error: --horizon: must be a positive")


def _library_modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.relative_to(PACKAGE).parts[0] != "cli":
            yield path


def _flag_like(node: ast.AST) -> str | None:
    if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.startswith("-"):
        return node.value
    if isinstance(node, ast.JoinedStr) and node.values and _flag_like(node.values[0]):
        return _flag_like(node.values[0])
    return None


def test_library_errors_do_not_name_command_line_flags():
    """Only the command line (``stt_codegen/cli/``) speaks in flags; the library names fields
    and parameters."""
    offenders = []
    for path in _library_modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call) and node.exc.args:
                flag = _flag_like(node.exc.args[0])
                if flag:
                    offenders.append(f"{path.relative_to(PACKAGE)}:{node.lineno}: {flag}")
    assert offenders == []


HEAVY = ("casadi", "sympy", "matplotlib", "numpy", "scipy", "control", "jinja2", "networkx",
         "distributed", "ompl", "pydantic")


def _imported_after(code: str) -> dict:
    probe = (f"import sys\n{code}\n"
             f"import json\nprint(json.dumps(sorted(m for m in {HEAVY!r} if m in sys.modules)))")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=120, cwd=PACKAGE.parent)
    assert proc.returncode == 0, proc.stderr
    return {"heavy": json.loads(proc.stdout.strip().splitlines()[-1]), "stdout": proc.stdout}


@pytest.mark.parametrize("code", [
    "import stt_codegen",
    "import stt_codegen.cli",
    "from stt_codegen.cli import main\nmain(['cases'])",
    "from stt_codegen.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass",
    "import stt_codegen\nstt_codegen.SpecError, stt_codegen.DesignError, stt_codegen.ToolchainError",
])
def test_help_and_cases_import_nothing_heavy(code):
    """``stt-codegen --help`` and ``cases`` import only the standard library (no timing)."""
    assert _imported_after(code)["heavy"] == []


def test_a_command_imports_its_module_only_when_chosen():
    out = _imported_after("from stt_codegen.cli import build_parser\n"
                          "build_parser(['cases'])\nassert 'stt_codegen.codegen' not in sys.modules")
    assert out["heavy"] == []
    parser = cli.build_parser(["generate"])
    args = parser.parse_args(["generate", "omnirobot-s1", "-o", "x", "--lang", "c"])
    assert args.languages == "c" and args.out_dir == "x" and callable(args.handler)


def test_design_without_plot_imports_no_plotting_and_no_simulator():
    """``stt-codegen design`` imports matplotlib only for ``--plot``, and neither MuJoCo nor
    the simulator (python-control) for a spec whose plant has equations; ``--dims`` is
    checked without matplotlib (docs/performance.md, command overhead; no timing)."""
    out = _imported_after("import contextlib, io\nfrom stt_codegen.cli import main\n"
                          "with contextlib.redirect_stdout(io.StringIO()):\n"
                          "    assert main(['design', 'omnirobot-s1', '--dims', '1,0']) == 0\n"
                          "print('mujoco' in sys.modules)")
    assert {"matplotlib", "control", "sympy", "jinja2"}.isdisjoint(out["heavy"]), out["heavy"]
    assert "casadi" in out["heavy"]                  # the probe did design (the tube's model)
    assert out["stdout"].splitlines()[0] == "False", "design imported mujoco"


def test_generate_imports_neither_sympy_nor_plotting_nor_the_simulator(tmp_path):
    """``stt-codegen generate`` prints C and Python from the pieces: SymPy (the proofs'
    printer), matplotlib and python-control are not imported (no timing)."""
    out = _imported_after("import contextlib, io\nfrom stt_codegen.cli import main\n"
                          "with contextlib.redirect_stdout(io.StringIO()):\n"
                          f"    assert main(['generate', 'omnirobot-s1', '-o', {str(tmp_path)!r}]) == 0")
    assert {"sympy", "matplotlib", "control", "scipy"}.isdisjoint(out["heavy"]), out["heavy"]
    assert {"casadi", "jinja2"} <= set(out["heavy"])        # the probe did generate
    assert (tmp_path / "omnirobot_s1.c").exists()


def test_every_command_is_configured_by_an_existing_function():
    import importlib
    for name, (help_text, target) in cli.COMMANDS.items():
        module, function = target.split(":")
        assert help_text and callable(getattr(importlib.import_module(module), function)), name


GLOBAL_STATE = r"""
import json, logging, os, signal, sys, warnings
import numpy as np
import matplotlib
# third-party packages first: their own import-time effects are not ours to judge
import casadi, sympy, scipy, control, jinja2
for optional in ("networkx", "distributed", "ompl", "tqdm"):
    try:
        __import__(optional)
    except ImportError:
        pass

def snapshot():
    return {
        "warnings": [repr(f) for f in warnings.filters],
        "numpy_err": np.geterr(),
        "numpy_print": repr(np.get_printoptions()),
        "numpy_random": repr(np.random.get_state()[1][:8].tolist()),
        "mpl_backend": repr(matplotlib.rcParams._get_backend_or_none()),
        # dict.items: RcParams.items() would itself resolve (and so set) the backend
        "mpl_rc": repr(sorted((k, repr(v)) for k, v in dict.items(matplotlib.rcParams))),
        "sys_path": list(sys.path),
        "environ": sorted(os.environ.items()),
        "recursion": sys.getrecursionlimit(),
        "sigint": repr(signal.getsignal(signal.SIGINT)),
        "logging": repr([logging.getLogger().level, logging.getLogger().handlers]),
        "float_repr": repr(0.1),
    }

before = snapshot()
import importlib, pkgutil, stt_codegen
names = sorted(m.name for m in pkgutil.walk_packages(stt_codegen.__path__, "stt_codegen."))
for name in names:
    importlib.import_module(name)
after = snapshot()
changed = sorted(k for k in before if before[k] != after[k])
print(json.dumps({"modules": len(names), "changed": changed}))
"""


@pytest.mark.slow
def test_no_module_changes_global_state_when_imported():
    """Import every module of the package: warnings, numpy, matplotlib, sys.path... unchanged."""
    proc = subprocess.run([sys.executable, "-c", GLOBAL_STATE], capture_output=True, text=True,
                          timeout=300, cwd=PACKAGE.parent)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["modules"] > 50
    assert result["changed"] == []
