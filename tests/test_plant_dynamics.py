"""Plant (14), the single integrator and the linear plant are written once
(runtime/dynamics.py): the simulation, the embedded closed loop (C) and Assumption 2
(SymPy) all derive from those Functions."""

from __future__ import annotations

import dataclasses
import shutil
import subprocess

import numpy as np
import pytest
import sympy as sp

from stt_codegen.codegen.emit import c_source
from stt_codegen.design.search import design_tube
from stt_codegen.embedded.programs import closed_loop_source
from stt_codegen.runtime.dynamics import input_matrix, linear_rhs, plant_function
from stt_codegen.runtime.plants import Disturbance, make_plant
from stt_codegen.spec.loader import LinearPlant, load_spec
from stt_codegen.proofs.assumption import plant_input_matrix

A = ((0.0, 1.0, 0.0), (-1.0, 0.0, 0.5), (0.0, 0.0, -0.25))
G = ((2.0, 0.5, 0.0), (0.0, 1.0, 0.0), (0.1, 0.0, 1.0))
C = (0.1, -0.2, 0.3)
CASES = [("omnidirectional", None), ("single-integrator", None),
         ("linear", LinearPlant(A, G, C))]


@pytest.mark.parametrize("model,linear", CASES, ids=[m for m, _ in CASES])
def test_the_simulated_plant_is_the_dynamics_function(model, linear):
    n = 3
    plant = make_plant(model, n, 0.1, seed=4, linear=linear)
    w = Disturbance(n, 0.1, 4)
    fn = plant_function(model, n, linear)
    rng = np.random.default_rng(0)
    for _ in range(20):
        t, x, u = rng.uniform(0, 5), rng.normal(size=n), rng.normal(size=n)
        expected = np.array(fn(x, u)).ravel() + w(t)
        assert np.array_equal(plant.dynamics(t, x, u), expected)


def test_the_omnidirectional_dynamics_is_eq_14():
    x, u = np.array([0.3, -1.0, 0.7]), np.array([1.0, 2.0, -0.5])
    c, s = np.cos(0.7), np.sin(0.7)
    rotation = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    assert np.allclose(np.array(plant_function("omnidirectional", 3)(x, u)).ravel(),
                       rotation @ u, rtol=0, atol=1e-15)
    assert np.allclose(np.array(input_matrix("omnidirectional", 3)(x)), rotation,
                       rtol=0, atol=0)


def test_assumption2_sees_the_same_input_matrix():
    x = sp.symbols("x1:4", real=True)
    g = plant_input_matrix("omnidirectional", 3, x)
    numeric = np.array(g.subs(x[2], 0.7).evalf(), dtype=float)
    assert np.allclose(numeric, np.array(input_matrix("omnidirectional", 3)([0, 0, 0.7])),
                       rtol=0, atol=1e-15)


@pytest.fixture(scope="module")
def omni():
    spec = load_spec("omnirobot-s1")
    return spec, design_tube(spec).tube


def test_the_closed_loop_program_prints_the_specs_plant(omni):
    spec, design = omni
    source = closed_loop_source(spec, design)
    assert c_source(plant_function("omnidirectional", 3)).strip() in source
    linear = dataclasses.replace(spec, plant_model="linear", linear_plant=LinearPlant(A, G, C))
    source = closed_loop_source(linear, design)
    assert c_source(linear_rhs(A, G, C)).strip() in source
    assert "x_dot = a x + c + g u + w" in source


def test_the_printed_c_plant_computes_what_the_simulation_does(tmp_path):
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (Debian package gcc)")
    fn = linear_rhs(A, G, C)
    x, u = [0.3, -1.25, 0.7], [1.0, 2.0, -0.5]
    main = (c_source(fn) + "\n#include <stdio.h>\nint main(void) {\n"
            f"  const double x[3] = {{{', '.join(map(repr, x))}}};\n"
            f"  const double u[3] = {{{', '.join(map(repr, u))}}};\n"
            "  double y[3];\n  plant_rhs(x, u, y);\n"
            '  printf("%a %a %a\\n", y[0], y[1], y[2]);\n  return 0;\n}\n')
    (tmp_path / "p.c").write_text("#include <math.h>\n" + main)
    subprocess.run([cc, "-std=c99", "-O0", "-ffp-contract=off", "-o", str(tmp_path / "p"),
                    str(tmp_path / "p.c"), "-lm"], check=True)
    out = subprocess.run([str(tmp_path / "p")], check=True, capture_output=True, text=True)
    got = [float.fromhex(v) for v in out.stdout.split()]
    assert got == list(np.array(fn(x, u)).ravel())
