"""The bundled specs: the paper's case study (section V), one TOML file per start set, and
two second-order cases (docs/second-order.md)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["bundled_cases", "bundled_fleet_bytes", "bundled_fleets", "bundled_folder",
           "bundled_spec_bytes"]


def bundled_cases() -> list[str]:
    """Names of the bundled specs (``omnirobot-s1``, ...), sorted; load one with
    :func:`stt_codegen.load_spec`.

    Returns
    -------
    list of str
        The case names, sorted, without the ``.toml`` suffix.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> "omnirobot-s1" in stt.bundled_cases()
    True
    >>> stt.load_spec(stt.bundled_cases()[0]).name
    'crossing-moving'
    """
    folder = resources.files(__name__)
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def bundled_folder() -> Path:
    """The folder of the bundled specs (and of the files they name, such as a MuJoCo
    model), in the installed package.

    Returns
    -------
    pathlib.Path
    """
    return Path(str(resources.files(__name__)))


def bundled_spec_bytes(name: str) -> bytes:
    """The bytes of the bundled spec ``name`` (one of :func:`bundled_cases`).

    Parameters
    ----------
    name : str
        A bundled case's name, without ``.toml`` (one of :func:`bundled_cases`).

    Returns
    -------
    bytes
        The TOML text of the spec, as stored in the package.

    Raises
    ------
    FileNotFoundError
        ``name`` is no bundled case.
    """
    return resources.files(__name__).joinpath(name + ".toml").read_bytes()


def bundled_fleets() -> list[str]:
    """Names of the bundled fleet specs (``swap-fleet``, ``warehouse-fleet``), sorted; load one with
    :func:`stt_codegen.load_fleet`.

    Returns
    -------
    list of str
        The fleet names, sorted, without the ``.toml`` suffix.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> stt.bundled_fleets()
    ['swap-fleet', 'warehouse-fleet']
    """
    folder = resources.files(__name__).joinpath("fleets")
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def bundled_fleet_bytes(name: str) -> bytes:
    """The bytes of the bundled fleet spec ``name`` (one of :func:`bundled_fleets`).

    Parameters
    ----------
    name : str
        A bundled fleet's name, without ``.toml``.

    Returns
    -------
    bytes
        The TOML text, as stored in the package.
    """
    return resources.files(__name__).joinpath("fleets", name + ".toml").read_bytes()
