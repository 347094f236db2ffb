"""``import_pointmaze`` / ``stt-codegen import pointmaze``: gymnasium-robotics' PointMaze mazes
as specs that design and run, the walls where gymnasium-robotics' own builder puts them."""

from __future__ import annotations

import sys
import tomllib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.cli import main
from stt_codegen.errors import SpecError
from stt_codegen.pointmaze import import_pointmaze, pointmaze_names, wall_boxes

try:
    import gymnasium_robotics  # noqa: F401
    HAVE_MAZES = True
except ImportError:
    HAVE_MAZES = False
needs_mazes = pytest.mark.skipif(not HAVE_MAZES, reason='gymnasium-robotics is not installed: '
                                                       'pip install ".[mujoco]"')

MAP = [[1, 1, 1, 1, 1, 1],
       [1, 0, 1, 1, 0, 1],
       [1, 0, 0, 1, 0, 1],
       [1, 1, 1, 1, 1, 1]]


def test_wall_boxes_cover_each_wall_cell_once_with_fewer_boxes():
    boxes = wall_boxes(MAP)
    covered = np.zeros((4, 6), dtype=int)
    for i0, i1, j0, j1 in boxes:
        covered[i0:i1 + 1, j0:j1 + 1] += 1
    assert (covered == (np.array(MAP) == 1)).all()
    assert len(boxes) < int((np.array(MAP) == 1).sum())
    # the walls of the first and last rows are one run each; the pillar (1, 2)-(2, 3) too
    assert (0, 0, 0, 5) in boxes and (3, 3, 0, 5) in boxes


def _cells(boxes, lower, upper, step=0.05):
    """Grid points (cell centres of a fine grid) inside the union of boxes."""
    xs = np.arange(lower[0] + step / 2, upper[0], step)
    ys = np.arange(lower[1] + step / 2, upper[1], step)
    x, y = np.meshgrid(xs, ys)
    inside = np.zeros_like(x, dtype=bool)
    for lo, hi in boxes:
        inside |= (x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1])
    return inside


@needs_mazes
@pytest.mark.parametrize("name", ["UMaze", "Medium"])
def test_a_maze_imports_designs_and_is_satisfied(tmp_path, name):
    spec_path, model = tmp_path / "maze.toml", tmp_path / "models" / "maze.xml"
    model.parent.mkdir()
    doc = import_pointmaze(name, spec_path, mjcf=model)
    text = spec_path.read_text()
    assert "models/maze.xml" in text             # the model, relative to the spec
    assert tomllib.loads(text) == doc
    spec = stt.load_spec(spec_path)
    assert spec.plant_model == "single-integrator"
    # the ball's radius from gymnasium-robotics' point.xml, plus the contact margin
    assert spec.robot.radius == pytest.approx(0.1 + 0.01)
    # the walls where gymnasium-robotics' builder put its blocks (MuJoCo's world frame)
    blocks = []
    for geom in ET.parse(model).iter("geom"):
        if geom.get("name", "").startswith("block_"):
            x, y, _ = (float(v) for v in geom.get("pos").split())
            hx, hy, _ = (float(v) for v in geom.get("size").split())
            blocks.append(((x - hx, y - hy), (x + hx, y + hy)))
    real = spec.robot
    walls = [(u.shape.lower, u.shape.upper) for u in real.unsafe_sets]
    space = real.state_space
    assert (_cells(walls, space.lower, space.upper)
            == _cells(blocks, space.lower, space.upper)).all()
    lows = np.min([b[0] for b in blocks], axis=0)
    highs = np.max([b[1] for b in blocks], axis=0)
    assert tuple(lows) == space.lower and tuple(highs) == space.upper
    design = stt.design_tube(spec)
    assert design.certificate.passed
    result = stt.simulate(design)
    assert result.satisfied and not result.collision


@needs_mazes
def test_cells_from_options_and_the_map():
    doc = import_pointmaze("UMaze", start=(3, 3), goal="1,1", prescribed_time=7.5,
                           rate_hz=200.0)
    assert doc["initial"]["state"] == [1.0, -1.0]         # column 3, row 3 of 5
    assert doc["target"]["lower"] == [-1.25, 0.75]
    assert doc["prescribed_time"] == 7.5 and doc["controller"]["rate_hz"] == 200.0
    marked = import_pointmaze("Medium_Diverse_G")         # its r cell is (1, 1)
    assert marked["initial"]["state"] == [-2.5, 2.5]


@needs_mazes
@pytest.mark.parametrize("kwargs, field, words", [
    ({"start": (0, 0)}, "start", "is a wall"),
    ({"start": "a"}, "start", "two integers"),
    ({"goal": (9, 1)}, "goal", "outside"),
    ({"goal": (1, 1)}, "goal", "is the start cell"),
    ({"contact_margin": 0.5}, "robot.radius", "no longer fits"),
])
def test_bad_options_are_refused(kwargs, field, words):
    with pytest.raises(SpecError) as info:
        import_pointmaze("UMaze", **kwargs)
    assert info.value.field == field and words in info.value.reason


def test_an_unknown_maze_lists_the_names():
    with pytest.raises(SpecError) as info:
        import_pointmaze("UMaze-v3")
    assert "UMaze, Open" in info.value.reason and "Large_Diverse_GR" in info.value.reason
    assert "Medium" in pointmaze_names()


def test_without_gymnasium_robotics_the_message_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "gymnasium_robotics.envs.maze", None)
    with pytest.raises(SpecError) as info:
        import_pointmaze("UMaze")
    assert 'pip install ".[mujoco]"' in info.value.reason


@needs_mazes
def test_the_command_writes_the_spec_or_nothing(tmp_path, capsys):
    out = tmp_path / "u.toml"
    assert main(["import", "pointmaze", "UMaze", "-o", str(out)]) == 0
    assert stt.load_spec(out).name == "pointmaze-umaze"
    bad = tmp_path / "bad.toml"
    for argv, words in ((["Nope"], "maps: UMaze"), (["UMaze", "--start", "0,0"], "--start"),
                        (["UMaze", "--mjcf", str(tmp_path / "no" / "m.xml")], "--mjcf")):
        assert main(["import", "pointmaze", *argv, "-o", str(bad)]) == 2
        err = capsys.readouterr().err
        assert words in err and "Traceback" not in err
        assert not bad.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["u.toml"]
