"""``occsurf render FILE (--lights LIGHTS.json | --preset NAME) --out IMAGE.png [--size W H] [--view NAME]
[--camera X Y Z [--target X Y Z] [--up X Y Z]] [--samples N] [--timeout SECONDS] [--strict] [--in-process]``.

Renders a STEP or IGES model under Warn's studio lights (course ch. 10) to a PNG, per pixel
(:func:`occsurf.bridge.rendering.lighting.render_model_lit`). The lights file is the JSON format
of :mod:`occsurf.algorithms.lighting.files` (validated: an error names the bad field); ``--preset``
starts from one of :data:`occsurf.algorithms.lighting.PRESETS` placed around the model instead.
The camera is a named view (``--view``, default ``iso``; ``top`` looks down -z at the whole model)
or an explicit ``--camera`` position looking at ``--target`` (default: the model's centre).

The file is read, meshed and rendered in a worker process (:func:`occsurf.bridge.isolation.run_jobs`
with the job :func:`occsurf.bridge.audit.render_file.render_job`): a crash inside OCC or VTK is one line ``occsurf: FILE: reason``.
Bad JSON, an unknown view, an unwritable output: one line on stderr, exit status 2, nothing written.
A model read around damage (see :mod:`occsurf.bridge.exchange.checks`) is rendered as read, with one line
``occsurf: FILE: warning: ...`` per warning on stderr; ``--strict`` refuses it instead (exit 2, no picture).
The PNG is written atomically (a reader never sees half a picture).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from ..audit.render_file import PRELOAD, RENDER_JOB
from ._common import (
    EXIT_ERROR,
    EXIT_OK,
    add_strict_option,
    error,
    output_problem,
    shown_path,
    strip_path,
    timeout_arg,
    worker_failure,
)

__all__ = ["add_parser", "run", "VIEW_NAMES"]

DEFAULT_TIMEOUT = 300.0
#: The named views (the same keys as :data:`occsurf.bridge.rendering.lighting.VIEWS`, listed here
#: so that the command-line process need not import NumPy to check ``--view``).
VIEW_NAMES = ("iso", "top", "bottom", "front", "back", "left", "right")
PRESET_NAMES = ("studio", "key-flaps", "highlight-check")


def _read_lights(path: Path) -> tuple[dict[str, Any] | None, str | None]:
    """The lights file parsed as JSON (validated later, in the worker), or why it cannot be."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        return None, f"cannot read the lights file: {getattr(err, 'strerror', None) or err}"
    try:
        return json.loads(text), None
    except json.JSONDecodeError as err:
        return None, f"not valid JSON ({err.msg} at line {err.lineno}, column {err.colno})"


def run(ns: argparse.Namespace) -> int:
    """``occsurf render``: check the arguments here, render in a worker, print one line."""
    from ..exchange.files import input_problem
    from ..isolation import ERROR, OK, run_jobs

    src, out = Path(ns.input), Path(ns.out)
    if ns.view not in VIEW_NAMES:
        error(f"--view: unknown view {ns.view!r}; expected one of {', '.join(VIEW_NAMES)}")
        return EXIT_ERROR
    if ns.preset is not None and ns.preset not in PRESET_NAMES:
        error(f"--preset: unknown preset {ns.preset!r}; expected one of {', '.join(PRESET_NAMES)}")
        return EXIT_ERROR
    lights = None
    if ns.lights is not None:
        lights, why = _read_lights(Path(ns.lights))
        if why is not None:
            error(f"{ns.lights}: {why}")
            return EXIT_ERROR
    why = output_problem(out)
    if why is not None:
        error(f"{out}: cannot write the picture there ({why})")
        return EXIT_ERROR
    why = input_problem(src)
    if why is not None:
        error(f"{shown_path(src)}: {why}")
        return EXIT_ERROR
    if ns.target is not None and ns.camera is None:
        error("--target needs --camera (a named --view always looks at the model's centre)")
        return EXIT_ERROR
    camera = None if ns.camera is None else {"position": ns.camera, "target": ns.target, "up": ns.up}
    item = {"input": str(src), "output": str(out), "lights": lights, "preset": ns.preset, "size": list(ns.size),
            "view": ns.view, "camera": camera, "samples": ns.samples, "strict": ns.strict}
    [outcome] = run_jobs(RENDER_JOB, [item], timeout=ns.timeout, isolate=not ns.in_process, preload=PRELOAD)
    if outcome.status != OK:
        why = (strip_path(outcome.error or "unknown error", src) if outcome.status == ERROR else
               worker_failure(outcome, ns.timeout, task="reading and rendering this file", process="worker"))
        where: Path | str = src
        if outcome.status == ERROR and outcome.error:
            if outcome.error.startswith(("lights", "ambient", "material", "two_sided")):
                where = ns.lights
            elif outcome.error.startswith(str(out) + ": "):  # writing the picture failed
                where, why = out, strip_path(outcome.error, out)
        error(f"{where}: {why}")
        return EXIT_ERROR
    r = outcome.value
    for w in r.get("warnings", ()):
        error(f"{src}: warning: {w}")
    sys.stdout.write(f"wrote {out} ({r['size'][0]} x {r['size'][1]}, {r['faces']} faces, {r['triangles']} triangles, "
                     f"{r['lights']} lights; render {r['render_seconds']:.2f} s)\n")
    sys.stdout.flush()
    return EXIT_OK


# ---------------------------------------------------------------------------------------- parser
def _size_arg(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of pixels from 16 to 16384, got {text!r}") from None
    if not 16 <= n <= 16384:
        raise argparse.ArgumentTypeError(f"expected a number of pixels from 16 to 16384, got {n}")
    return n


def _samples_arg(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer from 0 to 16, got {text!r}") from None
    if not 0 <= n <= 16:
        raise argparse.ArgumentTypeError(f"expected an integer from 0 to 16, got {n}")
    return n


def _coord_arg(text: str) -> float:
    import math

    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return x


def add_parser(sub: Any) -> None:
    """Register ``render`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    r = sub.add_parser(
        "render",
        help="render a STEP/IGES model under Warn's studio lights (course ch. 10) to a PNG",
        description=("Per-pixel picture of the model under the lights of a JSON lights file (Warn's controls: "
                     "direction and concentration, flaps, cones, fall-off, coloured lights) or a preset, from a "
                     "named view or an explicit camera. Exit status 0 when the picture was written, 2 otherwise."),
    )
    r.add_argument("input", metavar="FILE", help="STEP or IGES file")
    src = r.add_mutually_exclusive_group(required=True)
    src.add_argument("--lights", metavar="LIGHTS.json", help="the lights file (JSON; see the README)")
    src.add_argument("--preset", metavar="NAME",
                     help=f"a lighting preset placed around the model instead: {', '.join(PRESET_NAMES)}")
    r.add_argument("--out", required=True, metavar="IMAGE.png", help="where to write the picture (PNG)")
    r.add_argument("--size", nargs=2, type=_size_arg, default=[1600, 1200], metavar=("W", "H"),
                   help="picture size in pixels (default 1600 1200)")
    r.add_argument("--view", default="iso", metavar="NAME",
                   help=f"named view: {', '.join(VIEW_NAMES)} (default iso; top looks down -z at the whole model)")
    r.add_argument("--camera", nargs=3, type=_coord_arg, metavar=("X", "Y", "Z"),
                   help="explicit camera position (overrides --view)")
    r.add_argument("--target", nargs=3, type=_coord_arg, metavar=("X", "Y", "Z"),
                   help="point the camera looks at (with --camera; default the model's centre)")
    r.add_argument("--up", nargs=3, type=_coord_arg, default=[0.0, 0.0, 1.0], metavar=("X", "Y", "Z"),
                   help="view-up direction of --camera (default 0 0 1)")
    r.add_argument("--samples", type=_samples_arg, default=4, metavar="N",
                   help="multisampling of the edges, 0 (off, ~4x faster on a CPU renderer) to 16 (default 4)")
    r.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop the worker after this long and report it (default {DEFAULT_TIMEOUT:g})")
    add_strict_option(r, writes=True)
    r.add_argument("--in-process", action="store_true",
                   help="read and render in this process, not in a worker (a crash inside OCC then ends it)")
    r.set_defaults(func=run)
