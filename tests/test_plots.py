"""The figures: the arena's dimensions chosen and validated, every obstacle in
every projection, obstacles numbered as the messages number them, one legend entry per
thing and legends off the data, u(t) in a run's figure, a plot when there is no design."""

from __future__ import annotations

import re
import subprocess
import sys
from functools import lru_cache

import numpy as np
import pytest
from conftest import arena_toml
from matplotlib.patches import Circle, Polygon, Rectangle

from stt_codegen.cli import main
from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.runtime import plots
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import load_spec, parse_spec

#: A 3-D arena with an obstacle of each kind, given on different dimensions: a box on
#: (x1, x2), a ball on (x1, x3), a polytope on all three (coarsely covered: a fast load),
#: a box on x3 alone.
MIXED_3D = """
name = "mixed3"
prescribed_time = 9.0
[state_space]
lower = [0.0, 0.0, -1.0]
upper = [5.0, 5.0, 1.0]
[initial]
lower = [0.0, 0.0, -0.1]
upper = [0.5, 0.5, 0.1]
[target]
lower = [4.5, 4.5, -0.5]
upper = [5.0, 5.0, 0.5]
[[obstacles]]
lower = [1.0, 4.0]
upper = [2.0, 5.0]
[[obstacles]]
center = [2.5, 0.5]
radius = 0.3
dims = [0, 2]
[[obstacles]]
vertices = [[3.0, 3.0, -0.5], [3.8, 3.0, -0.5], [3.0, 3.8, -0.5], [3.3, 3.3, 0.5]]
tolerance = 0.25
[[obstacles]]
lower = [0.8]
upper = [1.0]
dims = [2]
"""

#: The paper's method refuses this arena: obstacle 1 (the second entry) lies next to the
#: target. Obstacle 0 is a ball, so the numbering is not the order of the boxes.
NEAR_TARGET = arena_toml("near", extra="""
[[obstacles]]
center = [1.5, 3.0]
radius = 0.4
[[obstacles]]
lower = [4.0, 4.5]
upper = [4.45, 5.0]
[tube]
method = "paper"
""")


@lru_cache(maxsize=None)
def mixed_3d():
    return parse_spec(MIXED_3D)


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args],
                          capture_output=True, text=True, timeout=600)


def arena_of(fig):
    """The arena axes of a figure (added first)."""
    return fig.axes[0]


def obstacle_patches(ax) -> dict[int, object]:
    found = {}
    for patch in ax.patches:
        gid = patch.get_gid() or ""
        if gid.startswith("obstacle "):
            found[int(gid.split()[1])] = patch
    return found


def obstacle_labels(ax) -> dict[int, tuple[float, float]]:
    """Obstacle number -> where its label is, data coordinates."""
    found = {}
    for text in ax.texts:
        if text.get_gid() == "obstacle label":
            for number in text.get_text().split(", "):
                found[int(number)] = text.xy
    return found


def data_extent(patch) -> np.ndarray:
    """``[[x_min, y_min], [x_max, y_max]]`` of a patch, data coordinates."""
    return patch.get_path().get_extents(patch.get_patch_transform()).get_points()


# --------------------------------------------------------------------------- dimensions


@pytest.mark.parametrize("text", ["0", "0,0", "0,3", "-1,0", "0,1,2", "a,b", "", "0.5,1"])
def test_bad_dims_are_refused_naming_the_field(text):
    with pytest.raises(SpecError) as info:
        plots.parse_dims(text, 3)
    assert info.value.field == "dims"


def test_good_dims_and_the_default():
    assert plots.parse_dims("0,2", 3) == (0, 2)
    assert plots.parse_dims("2,0", 3) == (2, 0)
    assert plots.parse_dims(None, 3) == (0, 1)
    with pytest.raises(SpecError):          # a 1-D spec has no pair
        plots.parse_dims("0,1", 1)
    with pytest.raises(SpecError):          # the library checks too
        plots.arena_figure(load_spec("omnirobot-s1"), 1, (1, 1))


@pytest.mark.parametrize("command", [["design", "omnirobot-s1", "--plot", "x.png"],
                                     pytest.param(["simulate", "omnirobot-s1", "--backend",
                                                   "reference", "--plot", "x.png"],
                                                  marks=pytest.mark.slow),
                                     pytest.param(["demo", "--out", "demo"],
                                                  marks=pytest.mark.slow)])
def test_bad_dims_on_the_command_line_exit_2_before_any_work(tmp_path, command):
    out = subprocess.run([sys.executable, "-m", "stt_codegen.cli", *command, "--dims", "0,3"],
                         capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert out.returncode == 2
    assert out.stderr.startswith("error: --dims: ") and out.stderr.count("\n") == 1
    assert "Traceback" not in out.stderr and out.stdout == ""
    assert list(tmp_path.iterdir()) == []


def test_dims_reach_the_figure(tmp_path, monkeypatch, capsys):
    drawn = []
    monkeypatch.setattr(plots, "save", lambda fig, path: drawn.append(fig))
    assert main(["design", "omnirobot-s1", "--plot", str(tmp_path / "d.png"),
                 "--dims", "0,2"]) == 0
    (fig,) = drawn
    ax = arena_of(fig)
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("$x_{1}$", "$x_{3}$")
    assert "projection" in ax.get_title()
    assert ax.get_ylim() == pytest.approx((-1.2 - 0.048, 1.2 + 0.048))


# --------------------------------------------------------------------------- obstacles


@pytest.mark.parametrize("dims", [(0, 1), (0, 2), (1, 2), (2, 0)])
def test_every_obstacle_is_drawn_as_its_projection(dims):
    spec = mixed_3d()
    fig, _, ax = plots.arena_figure(spec, 1, dims)
    patches = obstacle_patches(ax)
    assert sorted(patches) == [0, 1, 2, 3]
    assert sorted(obstacle_labels(ax)) == [0, 1, 2, 3]
    for j, unsafe in enumerate(spec.unsafe_sets):
        expected = np.array([[unsafe.shape.lower[unsafe.dims.index(d)] if d in unsafe.dims
                              else spec.state_space.lower[d] for d in dims],
                             [unsafe.shape.upper[unsafe.dims.index(d)] if d in unsafe.dims
                              else spec.state_space.upper[d] for d in dims]])
        np.testing.assert_allclose(data_extent(patches[j]), expected, rtol=0, atol=1e-9)
        both = set(dims) <= set(unsafe.dims)
        kind = {"ball": Circle, "polytope": Polygon}.get(unsafe.kind, Rectangle) if both \
            else Rectangle
        assert type(patches[j]) is kind, (j, dims)


def test_obstacles_are_numbered_as_the_messages_number_them():
    spec = parse_spec(NEAR_TARGET)
    with pytest.raises(DesignError) as info:
        design_tube(spec)
    (named,) = {int(j) for j in re.findall(r"obstacle (\d+)", str(info.value))}
    assert named == 1
    fig = plots.rejected_figure(spec, info.value)
    labels = obstacle_labels(arena_of(fig))
    assert sorted(labels) == [0, 1]
    box = spec.unsafe_sets[named].shape
    x, y = labels[named]
    assert box.lower[0] < x < box.upper[0] and box.lower[1] < y < box.upper[1]
    # a design's certificate names its obstacles the same way
    spec = load_spec("omnirobot-s1")
    design = design_tube(spec)
    named = {int(m.name.split()[-1]) for m in design.certificate.margins
             if m.name.startswith("avoids obstacle")}
    labels = obstacle_labels(arena_of(plots.design_figure(design)))
    assert set(labels) == named == {0, 1, 2, 3}
    for j in named:
        box = spec.unsafe_sets[j].shape
        assert box.lower[0] < labels[j][0] < box.upper[0]
        assert box.lower[1] < labels[j][1] < box.upper[1]


# --------------------------------------------------------------------------- legends


def assert_legends_are_clean(fig) -> int:
    """Every legend: no label twice, and clear of every axes and of the arena's x label.

    Returns the number of legends.
    """
    fig.canvas.draw()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    for legend in legends:
        labels = [t.get_text() for t in legend.get_texts()]
        assert len(labels) == len(set(labels)), labels
        box = legend.get_window_extent()
        for ax in fig.axes:
            assert not box.overlaps(ax.get_window_extent()), labels
            assert not box.overlaps(ax.xaxis.label.get_window_extent()), labels
    return len(legends)


@pytest.mark.parametrize("dims", [(0, 1), pytest.param((0, 2), marks=pytest.mark.slow)])
@pytest.mark.slow
def test_design_legends_have_one_entry_per_thing_outside_the_axes(dims):
    for spec in (load_spec("omnirobot-s1"), mixed_3d()):
        fig = plots.design_figure(design_tube(spec), dims)
        assert assert_legends_are_clean(fig) == 2
        arena = [t.get_text() for t in arena_of(fig).get_legend().get_texts()]
        assert arena.count(plots.OBSTACLE_LABEL) == 1
        assert "tube box (certified enclosure)" in arena


@pytest.fixture(scope="module")
def short_run():
    design = design_tube(load_spec("omnirobot-s2"))
    return design, simulate(design, backend="reference", horizon=1.0)


def test_run_figure_has_u_of_t_with_one_line_per_input(short_run):
    design, result = short_run
    fig = plots.run_figure(design, result, (1, 2))
    assert assert_legends_are_clean(fig) == 3     # arena, the tube plots, u(t)
    (u_ax,) = [ax for ax in fig.axes if ax.get_ylabel().startswith("u")]
    lines = [line for line in u_ax.get_lines() if line.get_label() != "$t_c$"]
    assert [line.get_label() for line in lines] == ["v1", "v2", "omega"]
    for k, line in enumerate(lines):
        np.testing.assert_array_equal(line.get_xdata(), result.trajectory.t)
        np.testing.assert_array_equal(line.get_ydata(), result.trajectory.u[:, k])
    assert u_ax.get_xlabel() == "t [s]"
    arena = arena_of(fig)
    trajectory = next(line for line in arena.get_lines() if line.get_label() == "trajectory")
    np.testing.assert_array_equal(trajectory.get_xydata(), result.trajectory.x[:, [1, 2]])


# --------------------------------------------------------------------------- no design


@pytest.mark.parametrize("command", ["design", pytest.param("simulate", marks=pytest.mark.slow)])
@pytest.mark.slow
def test_plot_without_a_design_shows_the_rejected_tube(command, tmp_path):
    spec_file = tmp_path / "near.toml"
    spec_file.write_text(NEAR_TARGET)
    png = tmp_path / "near.png"
    out = run_cli(command, str(spec_file), "--plot", str(png))
    assert out.returncode == 1 and "Traceback" not in out.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    lines = out.stderr.splitlines()
    assert lines == [f"plot written to {png}: it shows the best rejected tube",
                     "error: obstacle 1 comes within 0.1 of the target box eta +- d_T: "
                     "shrink target.half_width"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["near.png", "near.toml"]


def test_rejected_figure_has_the_reason_in_its_title():
    spec = parse_spec(NEAR_TARGET)
    with pytest.raises(DesignError) as info:
        design_tube(spec)
    fig = plots.rejected_figure(spec, info.value)
    title = " ".join(fig.get_suptitle().split())
    assert title == f"no design: {info.value}"
    # a 2-D arena is no projection, and says none
    assert arena_of(fig).get_title() == "near: NO DESIGN (obstacle at target), the best " \
                                        "rejected tube"


def test_design_plot_when_nothing_was_tried_writes_nothing_and_says_so(tmp_path):
    spec_file = tmp_path / "reversed.toml"
    spec_file.write_text(arena_toml("reversed", 9.0, '[plant]\nmodel = "linear"\n'
                                    'g = [[-1.0, 0.0], [0.0, -1.0]]\n'))
    png = tmp_path / "reversed.png"
    out = run_cli("design", str(spec_file), "--plot", str(png))
    assert out.returncode == 1 and not png.exists()
    first, error = out.stderr.splitlines()
    assert first == f"no plot written to {png}: no tube was tried"
    assert error.startswith("error: plant.g: ")
