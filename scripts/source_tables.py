"""What the converters of public data sets share: finding a source file in a checkout, warning when it is not
the file the converter was written for, reading a numeric column, and the command line that converts each
source file into a rodlab file. Imported by the ``scripts/convert_*.py`` next to it."""
from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path
from typing import Callable

import numpy as np

from rodlab.core.fileio import atomic_write_text


def find_source(src: Path, name: str, repository: str) -> Path:
    """The first file called ``name`` below ``src``; exits naming the repository to check out otherwise."""
    hits = sorted(src.rglob(name))
    if not hits:
        raise SystemExit(f"{src}: no {name} below it; give a checkout of {repository}")
    return hits[0]


def warn_if_changed(path: Path, sha256: str) -> None:
    """A warning on stderr when ``path`` is not the file (by its sha256) the converter was written for."""
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest != sha256:
        print(f"warning: {path} differs from the file this script was written for (sha256 {digest})",
              file=sys.stderr)


def column(rows: list[dict], key: str, path: Path, decimal_comma: bool = False) -> np.ndarray:
    """Column ``key`` of csv ``rows`` as floats; exits naming the file and column when it is absent or not numeric."""
    try:
        return np.array([float(r[key].replace(",", ".") if decimal_comma else r[key]) for r in rows])
    except KeyError:
        raise SystemExit(f"{path}: no column {key!r}") from None
    except ValueError as e:
        raise SystemExit(f"{path}: column {key!r}: {e}") from None


def convert_main(argv, doc: str, default_out: str, sources: dict, repository: str,
                 convert: Callable[[Path, str], str], out_name: Callable[[str], str]) -> int:
    """``SRC_DIR [-o OUT]``: each ``{key: source file name}`` converted by ``convert(path, key)`` and written
    atomically to ``OUT/out_name(key)``."""
    ap = argparse.ArgumentParser(description=doc.split("\n")[0])
    ap.add_argument("source", type=Path, help="checkout of the source repository")
    ap.add_argument("-o", "--out", type=Path, default=Path(default_out))
    a = ap.parse_args(argv)
    for key, name in sources.items():
        text = convert(find_source(a.source, name, repository), key)
        print(f"wrote {atomic_write_text(a.out / out_name(key), text)}")
    return 0
