"""The ``occsurf`` command line.

::

    occsurf --version
    occsurf inspect [FILE|DIR ...] [--json | --jsonl] [--samples N] [--timeout SECONDS] [--strict] [--in-process]
    occsurf fill IN --out OUT.step [--faces I ...] [--all-loops] [--no-occ] [--json] [--timeout SECONDS] [--strict]
                 [--in-process]
    occsurf match IN --face I --to J --out OUT.step [--continuity G0|G1|G2|G3] [--preserve-opposite none|G0|G1|G2]
                  [--average] [--tol-g0 D] [--tol-g1 DEG] [--tol-g2 PCT] [--sharp-deg DEG] [--json] [--timeout S]
                  [--strict] [--in-process]
    occsurf repair IN --preset catia|class-a|mechanical --out OUT.step [--max-change D] [--json] [--timeout S]
                   [--strict] [--in-process]
    occsurf fit DATA --tol T --out OUT.step [--json] [--ctrl NU NV] [--degree D] [--smooth S] [--fix-boundary]
                [--timeout SECONDS] [--strict] [--in-process]
    occsurf render FILE (--lights LIGHTS.json | --preset NAME) --out IMAGE.png [--size W H] [--view NAME]
                   [--timeout SECONDS] [--strict] [--in-process]
    occsurf demo [--out DIR] [--only NAME ...]
    occsurf check FILE_OR_DIR ... [--out DIR] [--json | --jsonl] [--faces N ...] [--fail-on PRESET] [--no-pictures]
                  [--timeout S] [--strict] [--in-process]
    occsurf audit PATH... --out RESULTS [--scheduler ADDRESS] [--workers N] [--timeout S] [--resume] [--checks LIST]
    occsurf convert IN OUT [--unit UNIT] [--digits N] [--timeout S] [--strict] [--in-process]

One module per command, each holding its parser and a thin handler that calls the library (the command
line is a leaf: nothing outside this package imports it; ``[tool.importlinter]`` in pyproject.toml):

===============  ==================================================================================
:mod:`.inspect`  faces of STEP/IGES files, our evaluation against OCC's
                 (:func:`occsurf.bridge.validation.files.inspect_files`)
:mod:`.fill`     fill the holes of a model (:func:`occsurf.bridge.modeling.fill.fill_model`)
:mod:`.fit`      fit data to a surface within a tolerance (:func:`occsurf.bridge.modeling.fit.fit_input`)
:mod:`.render`   a model under Warn's lights to a PNG (:func:`occsurf.bridge.rendering.lighting.render_lit`)
:mod:`.demo`     the picture gallery (:func:`occsurf.examples.gallery.run_demos`)
:mod:`.audit`    corpora on Dask, Parquet results (:func:`occsurf.bridge.audit.audit`)
:mod:`.check`    surface-quality report, page and JSON (:func:`occsurf.bridge.quality.check_files.check_file`)
:mod:`.convert`  STEP <-> IGES keeping structure, names, colours, units (:func:`occsurf.bridge.exchange.convert.convert`)
:mod:`._common`  exit codes, file arguments, tables, one-line errors, streamed output
===============  ==================================================================================

Errors are one line each on stderr, ``occsurf: PATH: reason``; the exit status is 0 on success and
2 when some input could not be processed or an argument is wrong (:data:`._common.EXIT_ERROR`).
Untrusted files are read in a worker process (:mod:`occsurf.bridge.isolation`), so a crash inside
OCC costs one file, not the command.

Only the standard library is imported at module level, so parsing and ``occsurf --help`` stay
instant; a command imports NumPy and OCC when it runs. Untrusted input is only ever parsed by OCC in
the worker; ``convert`` writes its output and reads that (trusted) file back in its own process. A new command adds a module
with ``add_parser(sub)`` (its parser, with a ``func`` default) and registers it in
:func:`build_parser`.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from . import audit, check, convert, demo, fill, fit, inspect, match, render, repair
from ._common import EXIT_ERROR, OneLineParser, guarded

__all__ = ["main", "console", "build_parser"]


def build_parser() -> argparse.ArgumentParser:
    """The ``occsurf`` parser: one sub-command per module, plus the hidden reader command."""
    parser = OneLineParser(
        prog="occsurf",
        description="Spline surfaces of the SIGGRAPH '91 course C25, bridged to OpenCascade.",
    )
    parser.add_argument("--version", action=_VersionAction, help="print occsurf's version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    inspect.add_parser(sub)
    demo.add_parser(sub)
    fill.add_parser(sub)
    match.add_parser(sub)
    repair.add_parser(sub)
    fit.add_parser(sub)
    render.add_parser(sub)
    audit.add_parser(sub)
    check.add_parser(sub)
    convert.add_parser(sub)
    inspect.add_worker_parser(sub)  # internal, no help= so it stays out of the listing
    return parser


class _VersionAction(argparse.Action):
    """``--version``: the version is looked up only when asked for (``--help`` stays instant)."""

    def __init__(self, option_strings: Sequence[str], dest: str, **kwargs: object) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)  # type: ignore[arg-type]

    def __call__(self, parser: argparse.ArgumentParser, namespace: object, values: object,
                 option_string: str | None = None) -> None:
        print(f"occsurf {_version()}")
        parser.exit()


def _version() -> str:
    """The installed distribution's version (its metadata), else the package's ``__version__``."""
    from importlib import metadata

    import occsurf

    try:
        return metadata.version("occsurf")
    except metadata.PackageNotFoundError:  # a source checkout that is not installed
        return occsurf.__version__


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``occsurf`` command line; returns the exit status (never raises for bad input)."""
    parser = build_parser()
    try:
        ns = parser.parse_args(argv)
    except SystemExit as exc:  # --help, or a usage error (argparse printed it)
        return exc.code if isinstance(exc.code, int) else EXIT_ERROR
    func = getattr(ns, "func", None)
    if func is None:
        parser.print_usage(sys.stderr)
        print("occsurf: error: a command is required (e.g. 'occsurf inspect')", file=sys.stderr)
        return EXIT_ERROR
    code = guarded(func, ns)
    _forget_handled_interrupts()
    return code


#: Exit statuses of a command that handled SIGINT (130) or SIGTERM (143) and cleaned up after itself.
INTERRUPTED = (128 + 2, 128 + 15)


def console(argv: Sequence[str] | None = None) -> None:
    """The ``occsurf`` executable (and ``python -m occsurf.bridge.cli``): :func:`main`, then exit.

    After an interrupt the command handled (130, 143: its cluster closed, what finished flushed) the
    process ends by ``os._exit`` once stdout and stderr are flushed, without the interpreter's
    finalization: a daemon thread still inside a C call when finalization begins (a thread of
    Dask's or of a library below it, which we neither own nor can join) can abort the process there
    with "Fatal Python error: ... the GIL is released ... Python runtime state: finalizing", exit
    -6 instead of 143 (seen once in about 50 SIGTERM trials of CI's
    ``test_signals_at_random_moments_end_the_run_promptly``). Every other status exits normally.
    """
    code = main(argv)
    if code in INTERRUPTED:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):  # a closed pipe: nothing more can be said on it
                pass
        os._exit(code)
    sys.exit(code)


def _forget_handled_interrupts() -> None:
    """Let the exit status we return stand after a Ctrl-C or SIGTERM the command handled.

    CPython (3.8 on) remembers a ``KeyboardInterrupt`` that ended a string ``exec``/``eval``
    (``PyRun_String``: the methods dataclasses and namedtuples generate while modules import, as
    NumPy, SciPy and pyarrow do on a command's first use) even when a caller caught it; under
    ``python -m`` its ``Py_RunMain`` then ends the process by SIGINT (status -2) whatever status it
    was given. An audit's SIGTERM handled that way ended with -2 instead of 143 (the CI flake of
    ``test_signals_at_random_moments_end_the_run_promptly``). The flag is cleared at the start of
    every string exec, and an exec that ends normally leaves it clear: the command is over, every
    interrupt it saw was handled.
    """
    exec("")  # noqa: S102 - an empty string: nothing runs; see above
