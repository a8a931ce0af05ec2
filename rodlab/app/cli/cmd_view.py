"""``rodlab view``: a 3-D picture of a field file of ``rodlab fea --fields`` (pyvista, the ``viz`` extra)."""
from __future__ import annotations

import argparse

from ...core.errors import RodlabError
from ...core.view3d import CAMERAS, LOAD_KEYS, parse_load, read_field_view, render_view

__all__ = ["register"]


def _scale(value: str):
    if value == "auto":
        return None
    try:
        s = float(value)
    except ValueError:
        s = float("nan")
    if not (s > 0 and s < float("inf")):
        raise argparse.ArgumentTypeError(f"expected 'auto' or a positive number, got {value!r}")
    return s


def register(sub) -> None:
    p = sub.add_parser("view", help="picture of FEA fields (*.vtu / *.vtp of rodlab fea --fields): deformed rod, "
                                    "stress colours (viz extra)",
                       description="Draw one load case of a field file: the deformed rod (exaggerated, the factor "
                                   "written in the picture) over its undeformed outline, coloured by von Mises stress "
                                   "or displacement, parts labelled, the ball's displacement as a red arrow, a colour "
                                   "bar with units. With -o it renders off-screen (no display needed: VTK's EGL or "
                                   "OSMesa, see docs/fea.md); without, it opens an interactive window.")
    p.add_argument("fields_file", metavar="FIELDS",
                   help="a *.vtu (solid model) or *.vtp (frame centreline) from rodlab fea --fields")
    p.add_argument("--load", default="y", metavar="CASE",
                   help=f"load case: x, y, z (unit force along x, y, z of {{T}}) or one of {', '.join(LOAD_KEYS)} "
                        "(gx: 1 g0 along x); default y")
    p.add_argument("--colour", "--color", dest="colour", choices=["stress", "displacement"], default="stress",
                   help="colour by von Mises stress (default; solid: at the nodes, frame: the sections' outer fibre) "
                        "or by displacement")
    p.add_argument("--scale", type=_scale, default=None, metavar="auto|FACTOR",
                   help="displacement exaggeration (default auto: the largest displacement 8 %% of the rod's size)")
    p.add_argument("--view", choices=list(CAMERAS), default="auto",
                   help="camera: auto (across the ball's displacement), iso, xz (the bend plane), xy, yz")
    p.add_argument("-o", "--output", default=None, metavar="PNG", help="write the picture here (off-screen)")
    p.set_defaults(func=cmd_view)


def cmd_view(args: argparse.Namespace) -> int:
    load = parse_load(args.load)
    if args.output and not args.output.lower().endswith(".png"):
        raise RodlabError(f"-o {args.output}: the picture is a PNG; name it *.png")
    view = read_field_view(args.fields_file)
    out = render_view(view, args.output, load=load, colour=args.colour, scale=args.scale, camera=args.view)
    if out is not None:
        print(f"wrote {out}")
    return 0
