"""``occsurf convert IN OUT [--unit UNIT] [--digits N] [--timeout SECONDS] [--strict] [--allow-loss] [--in-process]``.

Converts a STEP or IGES file to STEP or IGES (the format of ``OUT`` by its suffix) with
:func:`occsurf.bridge.exchange.convert.convert`: assembly structure, names, colours, layers and the
input's unit (``--unit`` to change it) are kept; STEP reals get 17 significant digits (``--digits``).
``IN`` is read in a worker process (an untrusted file that crashes OCC costs the worker, not the
command); ``OUT`` is replaced atomically. A model with fewer faces than ``IN`` describes (faces OCC
refused: a B-spline of degree 1e9, decreasing knots) is not written unless ``--allow-loss``.

Output: one line ``IN (FORMAT, UNIT) -> OUT (FORMAT, UNIT): N faces, M free curves``, then one line per
property that could not be carried (``IGES has no assembly instances: 2 instances of 'plate' written
as copies``; ``IGES has no per-instance colour overrides: ...``; ``layers of 1 instances not carried:
OCC's STEP writer writes no layer on an instance, ...``), measured by reading ``OUT`` back (faces'
names, colours, layers, instances, areas and wires; free curves' colours and layers). Exit status 0 when ``OUT`` was written, 2 with one
line ``occsurf: PATH: reason`` on stderr when ``IN`` cannot be read, ``OUT`` cannot be written or an
argument is wrong.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..exchange.reading import TARGET_SUFFIXES
from ._common import EXIT_ERROR, EXIT_OK, add_strict_option, error, output_problem, shown_path, timeout_arg

__all__ = ["add_parser", "run", "DEFAULT_TIMEOUT", "UNITS"]

#: Seconds the reader process may take (``--timeout``).
DEFAULT_TIMEOUT = 300.0
#: ``--unit`` choices (the same as :data:`occsurf.bridge.exchange.xcaf.WRITE_UNITS`; kept here so the
#: command line does not import NumPy to build its parser; a test keeps the two equal).
UNITS = ("mm", "cm", "m", "km", "um", "inch", "ft", "mi", "mil", "uin")
#: What an output may be named: :data:`occsurf.bridge.exchange.reading.TARGET_SUFFIXES`, flat.
_OUT_SUFFIXES = tuple(s for suffixes in TARGET_SUFFIXES.values() for s in suffixes)


def run(ns: argparse.Namespace) -> int:
    """``occsurf convert``: read IN (in a worker), write OUT, print what was not carried."""
    out = Path(ns.output)
    if out.suffix.lower() not in _OUT_SUFFIXES:
        error(f"{shown_path(ns.output)}: expected an output file name ending in {', '.join(_OUT_SUFFIXES)}")
        return EXIT_ERROR
    problem = output_problem(out)
    if problem is not None:
        error(f"{shown_path(ns.output)}: {problem}")
        return EXIT_ERROR
    from occsurf.algorithms.errors import OccsurfError

    from ..exchange.convert import convert
    from ..messages import error_line

    before = _identity(out)
    try:
        report = convert(ns.input, ns.output, unit=ns.unit, digits=ns.digits, isolated=not ns.in_process,
                         timeout=ns.timeout, strict=ns.strict, allow_loss=ns.allow_loss)
    except KeyboardInterrupt:
        if _identity(out) != before:  # Ctrl-C after the atomic replace, while OUT was read back
            error(f"{shown_path(ns.output)}: written, but interrupted while reading it back: nothing was compared")
        raise
    except (OccsurfError, OSError) as err:
        message = error_line(err)
        shown = shown_path(ns.input)
        error(message if message.startswith((shown, str(ns.input), str(ns.output))) else f"{shown}: {message}")
        return EXIT_ERROR
    for w in report.warnings:
        error(f"{shown_path(ns.input)}: warning: {w}")
    lines = [f"{shown_path(ns.input)} ({report.source_format.upper()}) -> {shown_path(ns.output)} "
             f"({report.target_format.upper()}, {report.unit}): {report.n_faces} faces, "
             f"{report.n_edges} free curves, {report.seconds:.2f} s"]
    lines += report.not_carried
    sys.stdout.write("\n".join(lines) + "\n")
    sys.stdout.flush()
    return EXIT_OK


def _identity(path: Path) -> tuple[int, int, int] | None:
    """Inode, size and modification time of ``path`` (``None`` when absent): a replaced file differs."""
    try:
        st = path.stat()
    except OSError:
        return None
    return (st.st_ino, st.st_size, st.st_mtime_ns)


def _digits_arg(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer from 2 to 17, got {text!r}") from None
    if not 2 <= n <= 17:
        raise argparse.ArgumentTypeError(f"expected an integer from 2 to 17, got {n}")
    return n


def add_parser(sub: Any) -> None:
    """Register ``convert`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    p = sub.add_parser(
        "convert",
        help="convert STEP <-> IGES keeping assemblies, names, colours, layers and units",
        description=("Convert a STEP or IGES file to STEP or IGES (OUT's suffix decides), keeping the assembly "
                     "structure, names, colours, layers and the unit; prints one line per property the "
                     "output could not carry. Exit status 0 when OUT was written, 2 otherwise."),
    )
    p.add_argument("input", metavar="IN", help="STEP (.step, .stp) or IGES (.iges, .igs) file")
    p.add_argument("output", metavar="OUT", help="output file: .step/.stp/.p21 or .iges/.igs; replaced atomically")
    p.add_argument("--unit", choices=UNITS, default=None,
                   help="length unit of OUT (default: the unit IN declares)")
    p.add_argument("--digits", type=_digits_arg, default=None, metavar="N",
                   help="significant digits of STEP reals, 2 to 17 (default 17: lossless; IGES keeps 10)")
    p.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop reading IN after this long (default {DEFAULT_TIMEOUT:g})")
    add_strict_option(p, writes=True)
    p.add_argument("--allow-loss", action="store_true",
                   help="write the model even when it has fewer faces than the source describes (faces OCC "
                        "refused to read); refused otherwise, nothing written")
    p.add_argument("--in-process", action="store_true",
                   help="read IN in this process, not in a worker (a crash inside OCC then ends it)")
    p.set_defaults(func=run)
