"""The toolkit's version, in one module that imports nothing.

The front door re-exports it (``stt_codegen.__version__``); the code generator writes it
into every manifest and ``stt-codegen --version`` prints it. Keep it equal to
``[project] version`` of ``pyproject.toml``.
"""

__all__ = ["__version__"]

__version__ = "0.1.0"
