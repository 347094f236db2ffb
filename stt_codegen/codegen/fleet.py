"""One controller per robot of a fleet: a folder each, no shared state (docs/fleets.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from ..design.fleet import FleetDesign
from ..errors import SpecError
from .api import generate
from .options import LANGUAGES

__all__ = ["generate_fleet"]


def generate_fleet(fleet: FleetDesign, out_dir: str | Path,
                   languages: str | Sequence[str] = LANGUAGES,
                   precision: str = "double") -> dict[str, list[Path]]:
    """Write each robot's standalone controller into its own folder, ``out_dir/<robot>``.

    Each folder is what :func:`stt_codegen.generate` writes for that robot's design (its C
    and Python, its test vectors and manifest, named after the robot): the controllers
    share nothing and exchange nothing; each one's tube already keeps clear of the others'.

    Parameters
    ----------
    fleet : FleetDesign
        From :func:`stt_codegen.design_fleet`.
    out_dir : str or path
        The parent folder; created if missing (its parent must exist). Each robot's folder
        follows :func:`stt_codegen.generate`'s rules.
    languages : str or sequence of str, optional
        As :func:`stt_codegen.generate`.
    precision : {"double", "single"}, optional
        As :func:`stt_codegen.generate`.

    Returns
    -------
    dict of str to list of pathlib.Path
        Per robot name, the files written.

    Raises
    ------
    TypeError
        ``fleet`` is not a :class:`~stt_codegen.design.fleet.FleetDesign`.
    SpecError
        As :func:`stt_codegen.generate`; field ``out_dir`` when it is a file.

    Examples
    --------
    >>> import tempfile, stt_codegen as stt
    >>> fleet = stt.design_fleet("swap-fleet")
    >>> with tempfile.TemporaryDirectory() as out:
    ...     written = stt.generate_fleet(fleet, out, languages="python")
    ...     sorted(written), [p.name for p in written["east"]]
    (['east', 'west'], ['east.py', 'east_vectors.json', 'manifest.json'])
    """
    if not isinstance(fleet, FleetDesign):
        raise TypeError("generate_fleet(): parameter 'fleet' must be a FleetDesign (call "
                        f"stt_codegen.design_fleet first), not {type(fleet).__name__}")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise SpecError("out_dir", f"{str(out)!r} is a file, not a folder")
    out.mkdir(exist_ok=True)
    return {name: generate(design, out / name, languages=languages, precision=precision)
            for name, design in fleet.designs.items()}
