"""The argument parser class of the subcommands: it remembers each option's flag."""

from __future__ import annotations

import argparse
import functools

__all__ = ["CommandParser"]


class CommandParser(argparse.ArgumentParser):
    """An argument parser that remembers the option of each destination, ``flags[dest]``.

    The dictionary is shared with the parsers of nested subcommands (``bench arenas``), so
    an error about a library parameter (``SpecError("horizon", ...)``) can be reported
    with the flag the user typed (``--horizon``).

    Parameters
    ----------
    *args
        Passed to :class:`argparse.ArgumentParser`.
    flags : dict of str to str, optional
        The shared ``dest -> flag`` dictionary (a nested subcommand's parser gets its
        parent's); ``None`` starts an empty one.
    **kwargs
        Passed to :class:`argparse.ArgumentParser`.
    """

    def __init__(self, *args, flags: dict[str, str] | None = None, **kwargs) -> None:
        self.flags: dict[str, str] = {} if flags is None else flags
        super().__init__(*args, **kwargs)

    def add_argument(self, *args, **kwargs):
        action = super().add_argument(*args, **kwargs)
        if action.option_strings:
            self.flags.setdefault(action.dest, max(action.option_strings, key=len))
        return action

    def add_subparsers(self, **kwargs):
        kwargs.setdefault("parser_class", functools.partial(CommandParser, flags=self.flags))
        return super().add_subparsers(**kwargs)
