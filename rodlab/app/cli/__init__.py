"""The ``rodlab`` command line (prints; the library only logs)."""
from .main import build_parser, main

__all__ = ["main", "build_parser"]
