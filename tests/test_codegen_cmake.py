"""The generated CMakeLists.txt: a static library usable through add_subdirectory."""

from __future__ import annotations

import shutil
import subprocess

import pytest
from conftest import designed
from codegen_helpers import files_of, write

CMAKE = shutil.which("cmake")

APP = """#include <stdio.h>
#include "{p}.h"
int main(void) {{
  {p}_real x[{U}_N] = {{0}}, alpha[{U}_N_ALPHA] = {{0}}, u[{U}_N], next[{U}_N_ALPHA];
  int status = {p}_step(x, 0, 1e-3f, alpha, u, next);
  printf("status %d\\n", status);
  return status == {U}_STATUS_INVALID_INPUT ? 1 : 0;
}}
"""


@pytest.mark.skipif(CMAKE is None, reason="cmake missing: install the Debian package cmake")
@pytest.mark.parametrize("precision", ["double", "single"])
def test_add_subdirectory_and_standalone_ctest(precision, tmp_path):
    case = "omnirobot-s2"
    spec, _, _ = designed(case)
    p = spec.c_name
    write(tmp_path / "app" / "controller", files_of(case, precision))
    (tmp_path / "app" / "main.c").write_text(APP.format(p=p, U=p.upper()))
    (tmp_path / "app" / "CMakeLists.txt").write_text(
        "cmake_minimum_required(VERSION 3.13)\nproject(app C)\nadd_subdirectory(controller)\n"
        f"add_executable(app main.c)\ntarget_link_libraries(app PRIVATE {p})\n")
    for source, build in ((tmp_path / "app", tmp_path / "build-app"),
                          (tmp_path / "app" / "controller", tmp_path / "build-alone")):
        for cmd in ([CMAKE, "-S", str(source), "-B", str(build)],
                    [CMAKE, "--build", str(build)]):
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
            assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert (tmp_path / "build-app" / "controller" / f"lib{p}.a").exists()
    run = subprocess.run([str(tmp_path / "build-app" / "app")], capture_output=True, text=True)
    assert run.returncode == 0 and run.stdout.startswith("status "), run.stdout
    test = subprocess.run(["ctest", "--test-dir", str(tmp_path / "build-alone"),
                           "--output-on-failure"], capture_output=True, text=True, timeout=600)
    assert test.returncode == 0 and "100% tests passed" in test.stdout, test.stdout[-2000:]
