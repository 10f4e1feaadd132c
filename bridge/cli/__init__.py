"""The ``occsurf`` command line.

::

    occsurf inspect [FILE|DIR ...] [--json] [--samples N] [--timeout SECONDS] [--in-process]
    occsurf fill IN --out OUT.step [--all-loops] [--no-occ] [--json]

``inspect`` reads STEP and IGES files through :mod:`occsurf.bridge.exchange.step_iges` and prints, per face, the
surface type, degrees, poles, rational and periodic flags, OCC's continuity class and the largest
distance between our evaluation of the converted surface and OCC's evaluation of the original one
on an ``N x N`` grid, relative to the diagonal of the sampled points' bounding box
(:func:`occsurf.bridge.validation.deviation.surface_deviation`, ``max_point_rel``). The deviation is measured for
free-form faces only (B-spline and Bezier): their poles are the face's own data, so ours must
reproduce OCC's surface to round-off. Analytic faces (planes, cylinders, ...) convert to a
different parametrisation and show ``-``. Without arguments, ``inspect`` reads every STEP/IGES
file in the ``step_samples/`` folder (below the current directory, else the repository's).

Exit status: 0 when every file was read; 2 when at least one could not be (each such file gets one
line ``occsurf: PATH: reason`` on stderr and an ``error`` in the JSON, and the other files are still
reported), or when an argument is wrong.

Crash isolation
---------------
Python can catch exceptions, not a segmentation fault inside OCC (``shared/OCP_NOTES.md`` §7 lists
one; a malformed face can trigger others). So the files are read in a worker process
(``python -m occsurf.bridge.cli _inspect-worker``) that streams one JSON report per file back. If the worker
dies, the file it was reading is reported as an error naming the signal, and a new worker carries
on with the remaining files. ``--in-process`` reads in the calling process instead (no isolation;
handy under a debugger). :func:`inspect_files` is the in-process library entry.

Only the standard library is imported at module level, and the command-line process itself never
imports NumPy or OCC (the worker does): ``occsurf --help`` stays instant. New subcommands (``demo``,
``fill``) register themselves in :func:`build_parser` with a ``func`` default, as ``inspect`` does.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any, TextIO

__all__ = [
    "main",
    "build_parser",
    "inspect_files",
    "find_samples_dir",
    "FaceReport",
    "FileReport",
    "EXIT_OK",
    "EXIT_ERROR",
]

EXIT_OK = 0
#: Some file could not be read, or a command-line argument is wrong (argparse uses 2 as well).
EXIT_ERROR = 2

STEP_SUFFIXES = (".step", ".stp")
IGES_SUFFIXES = (".iges", ".igs")
SUFFIXES = STEP_SUFFIXES + IGES_SUFFIXES
#: Surface types whose poles are the face's own data (the deviation is measured only for these).
FREE_FORM = ("BSplineSurface", "BezierSurface")
SAMPLES_DIR = "step_samples"
DEFAULT_SAMPLES = 25
#: Seconds one file may take in the reader process before it is killed and reported as timed out
#: (a hang inside OCC must not hang the command); ``--timeout`` overrides it.
DEFAULT_TIMEOUT = 300.0
WORKER_COMMAND = "_inspect-worker"
#: Prefix of the worker's protocol lines on its stdout (anything else there is ignored).
_MARK = "\x1eoccsurf-worker "


# ---------------------------------------------------------------------------------------- results
@dataclass
class FaceReport:
    """One face as reported by ``inspect`` (JSON-safe values only).

    ``degree``, ``poles`` and ``rational`` describe the face's own B-spline/Bezier data and are
    ``None`` for analytic faces; ``max_deviation`` (relative) likewise, and also when it could not be
    measured (``error`` then says why).
    """

    index: int
    name: str | None
    surface_type: str
    degree: list[int] | None
    poles: list[int] | None
    rational: bool | None
    periodic: list[bool]
    continuity: str | None
    max_deviation: float | None
    max_d1_deviation: float | None = None
    max_d2_deviation: float | None = None
    max_normal_angle: float | None = None
    error: str | None = None

    @property
    def free_form(self) -> bool:
        return self.surface_type in FREE_FORM


@dataclass
class FileReport:
    """One file (or one argument that is not a readable file)."""

    path: str
    format: str | None = None
    error: str | None = None
    faces: list[FaceReport] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def n_free_form(self) -> int:
        return sum(f.free_form for f in self.faces)

    @property
    def worst_deviation(self) -> float | None:
        devs = [f.max_deviation for f in self.faces if f.max_deviation is not None]
        return max(devs) if devs else None

    def to_json(self) -> dict[str, Any]:
        return {
            "path": self.path,
            "format": self.format,
            "error": self.error,
            "n_faces": len(self.faces),
            "n_free_form": self.n_free_form,
            "worst_deviation": self.worst_deviation,
            "seconds": round(self.seconds, 4),
            "warnings": list(self.warnings),
            "faces": [asdict(f) for f in self.faces],
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> FileReport:
        names = {f.name for f in fields(FaceReport)}
        faces = [FaceReport(**{k: v for k, v in face.items() if k in names}) for face in data.get("faces", ())]
        return cls(path=data["path"], format=data.get("format"), error=data.get("error"), faces=faces,
                   warnings=list(data.get("warnings", ())), seconds=float(data.get("seconds", 0.0)))


# ---------------------------------------------------------------------------------------- helpers
def _one_line(err: BaseException | str) -> str:
    """An exception (or text) as one line; unexpected exceptions keep their type name."""
    if isinstance(err, BaseException):
        text = str(err).strip()
        from occsurf.algorithms.errors import OccsurfError

        if not isinstance(err, (OccsurfError, OSError)) or not text:
            text = f"{type(err).__name__}: {text}" if text else type(err).__name__
    else:
        text = str(err)
    return " ".join(text.split()) or "unknown error"


def _finite_or_none(x: Any) -> float | None:
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _strip_path(message: str, path: Path) -> str:
    """Drop a leading ``PATH: `` from a message: the CLI prints the path itself."""
    candidates = {str(path), os.fspath(path)}
    with contextlib.suppress(OSError):
        candidates.add(str(path.resolve()))
        candidates.add(str(path.absolute()))
    for c in sorted(candidates, key=len, reverse=True):
        if message.startswith(c + ": "):
            return message[len(c) + 2 :]
    return message


@contextlib.contextmanager
def _quiet_native_stdout() -> Iterator[None]:
    """Send what C++ code (OCC banners, ``printf``) writes to fd 1 to ``/dev/null`` meanwhile.

    Our own output (the table, the JSON document, the worker protocol) must be all that reaches
    stdout. Python's ``sys.stdout`` is flushed first so nothing is lost or reordered.
    """
    try:
        sys.stdout.flush()
        fd = sys.__stdout__.fileno() if sys.__stdout__ is not None else 1
        saved = os.dup(fd)
    except (OSError, ValueError, AttributeError):
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), fd)
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)


def find_samples_dir(cwd: Path | None = None) -> Path | None:
    """The ``step_samples/`` folder: below the current directory first, then the one shipped in the
    package (``occsurf/step_samples`` in a wheel, the repository's folder in a source checkout)."""
    import occsurf

    here = Path.cwd() if cwd is None else Path(cwd)
    shipped = [Path(p) / SAMPLES_DIR for p in occsurf.__path__]
    for candidate in (here / SAMPLES_DIR, *shipped):
        if candidate.is_dir():
            return candidate
    return None


def _files_in(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in SUFFIXES)


def _expand(args: Sequence[str]) -> list[tuple[str, Path | None, str | None]]:
    """``(shown path, path or None, error or None)`` for every argument, folders expanded."""
    out: list[tuple[str, Path | None, str | None]] = []
    for arg in args:
        path = Path(arg)
        try:
            if path.is_dir():
                files = _files_in(path)
                if not files:
                    out.append((arg, None, f"no STEP/IGES files ({', '.join(SUFFIXES)}) in this folder"))
                out.extend((str(f), f, None) for f in files)
            elif path.exists():
                out.append((arg, path, None))
            else:
                out.append((arg, None, "no such file or directory"))
        except OSError as err:  # unreadable folder, name too long, ...
            out.append((arg, None, f"cannot read: {err.strerror or err}"))
    return out


def _sniff_format(path: Path) -> str:
    """``'step'`` or ``'iges'`` from the suffix, else from the start of the file."""
    from occsurf.algorithms.errors import ExchangeError

    suffix = path.suffix.lower()
    if suffix in STEP_SUFFIXES:
        return "step"
    if suffix in IGES_SUFFIXES:
        return "iges"
    try:
        with open(path, "rb") as fh:
            head = fh.read(200)
    except OSError as err:
        raise ExchangeError(f"cannot read: {err.strerror or err}") from err
    if head.lstrip(b"\xef\xbb\xbf \t\r\n").upper().startswith(b"ISO-10303-21"):
        return "step"
    if head.split(b"\n", 1)[0][72:73] == b"S":  # IGES start section: 80 columns, 'S' in column 73
        return "iges"
    raise ExchangeError(f"not a STEP or IGES file (suffix {suffix or 'none'!r}, unrecognised header)")


# ---------------------------------------------------------------------------------------- inspect
def _inspect_face(face: Any, samples: int) -> FaceReport:
    surface_type = str(getattr(face, "surface_type", "Other"))
    surf = getattr(face, "surface", None)
    continuity = getattr(face, "continuity", None)
    error = getattr(face, "error", None)
    rep = FaceReport(
        index=int(face.index),
        name=(str(face.name) if getattr(face, "name", None) else None),
        surface_type=surface_type,
        degree=None,
        poles=None,
        rational=None,
        periodic=[bool(getattr(face, "u_periodic", False)), bool(getattr(face, "v_periodic", False))],
        continuity=None if continuity is None else str(continuity),
        max_deviation=None,
        error=None if error is None else _one_line(str(error)),
    )
    if surface_type not in FREE_FORM:
        return rep  # analytic or derived: no poles of its own, nothing exact to compare
    if surf is None:
        rep.error = rep.error or "the free-form face was not converted"
        return rep
    rep.degree = [int(surf.degree[0]), int(surf.degree[1])]
    rep.poles = [int(surf.n_poles[0]), int(surf.n_poles[1])]
    rep.rational = bool(surf.is_rational)
    try:
        from ..validation.deviation import surface_deviation

        dev = surface_deviation(surf, getattr(face, "occ_surface", None), samples=samples)
    except Exception as err:  # noqa: BLE001 - one bad face must not hide the others
        rep.error = f"deviation not measured: {_one_line(err)}"
        return rep
    rep.max_deviation = _finite_or_none(dev.max_point_rel)
    rep.max_d1_deviation = _finite_or_none(getattr(dev, "max_d1_rel", None))
    rep.max_d2_deviation = _finite_or_none(getattr(dev, "max_d2_rel", None))
    rep.max_normal_angle = _finite_or_none(getattr(dev, "max_normal_angle", None))
    if rep.max_deviation is None and rep.error is None:
        rep.error = "the deviation is not finite"
    return rep


def _inspect_file(shown: str, path: Path, samples: int) -> FileReport:
    import numpy as np

    report = FileReport(path=shown)
    with contextlib.suppress(Exception):  # load OCC outside the timing (a failure shows up below)
        from ..exchange import step_iges  # noqa: F401
        from ..validation import deviation  # noqa: F401
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"), _quiet_native_stdout():
            warnings.simplefilter("ignore")
            fmt = _sniff_format(path)
            report.format = fmt
            from ..exchange import step_iges as exchange

            model = (exchange.read_step if fmt == "step" else exchange.read_iges)(path)
            report.warnings = [_one_line(str(w)) for w in getattr(model, "warnings", None) or ()]
            for k, face in enumerate(model.faces):
                try:
                    report.faces.append(_inspect_face(face, samples))
                except Exception as err:  # noqa: BLE001
                    report.faces.append(FaceReport(
                        index=int(getattr(face, "index", k)), name=None,
                        surface_type=str(getattr(face, "surface_type", "Other")), degree=None, poles=None,
                        rational=None, periodic=[False, False], continuity=None, max_deviation=None,
                        error=_one_line(err)))
    except Exception as err:  # noqa: BLE001 - report, never crash, never a traceback
        report.error = _strip_path(_one_line(err), path)
    report.seconds = time.perf_counter() - t0
    return report


def inspect_files(args: Sequence[str], samples: int = DEFAULT_SAMPLES) -> list[FileReport]:
    """Inspect every file named in ``args`` (folders expanded), in this process.

    Never raises for a bad file: its report has ``error`` set. (A segmentation fault inside OCC
    still ends the process; the command line reads files in a worker process instead.)

    Parameters
    ----------
    args : sequence of str
        Files and folders (a folder stands for its STEP/IGES files, sorted).
    samples : int
        Grid size of the deviation check.

    Returns
    -------
    list of FileReport
    """
    return [_inspect_file(shown, path, samples) if path is not None else FileReport(path=shown, error=error)
            for shown, path, error in _expand(args)]


# ---------------------------------------------------------------------------------------- isolation
def _worker_main() -> int:
    """Worker loop: read ``{"files": [[shown, path], ...], "samples": N}`` from stdin, write a
    ``start`` line before each file and a ``report`` line after it."""
    job = json.loads(sys.stdin.read())
    samples = int(job["samples"])

    def send(msg: dict[str, Any]) -> None:
        sys.stdout.write(_MARK + json.dumps(msg) + "\n")
        sys.stdout.flush()

    # Load OCC and the reading stack before the first "start": --timeout measures reading a file,
    # not this process's start-up (seconds on a loaded machine; a failure shows up per file).
    with contextlib.suppress(Exception):
        from ..exchange import step_iges  # noqa: F401
        from ..validation import deviation  # noqa: F401
    for k, (shown, path) in enumerate(job["files"]):
        send({"start": k})
        try:
            report = _inspect_file(shown, Path(path), samples)
            payload = report.to_json()
            json.dumps(payload, allow_nan=False)  # fail here, per file, rather than in the parent
        except Exception as err:  # noqa: BLE001
            payload = FileReport(path=shown, error=_one_line(err)).to_json()
        send({"report": k, "data": payload})
    return EXIT_OK


def _worker_env() -> dict[str, str]:
    """The worker imports ``occsurf`` from the same place as this process."""
    import occsurf

    env = dict(os.environ)
    root = str(Path(occsurf.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join(x for x in (root, env.get("PYTHONPATH")) if x)
    return env


def _describe_exit(code: int) -> str:
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        return f"killed by {name}"
    return f"exit status {code}"


def _last_line(fh: Any) -> str:
    fh.seek(0)
    lines = [ln.strip() for ln in fh.read().decode("utf-8", "replace").splitlines() if ln.strip()]
    return lines[-1] if lines else ""


def _inspect_isolated(files: list[tuple[str, Path]], samples: int,
                      on_report: Callable[[int, FileReport], None], timeout: float = DEFAULT_TIMEOUT) -> None:
    """Inspect ``files`` in worker processes; calls ``on_report(k, report)`` for each, in order.

    A file that crashes the worker or takes longer than ``timeout`` seconds is reported as failed
    (the worker is killed) and a new worker continues with the files after it.
    """
    import threading

    todo = list(range(len(files)))
    while todo:
        job = {"samples": samples, "files": [[files[k][0], str(files[k][1])] for k in todo]}
        current: int | None = None
        done: set[int] = set()
        timed_out = threading.Event()
        watchdog: threading.Timer | None = None

        def arm(p: subprocess.Popen) -> threading.Timer:
            def fire() -> None:
                timed_out.set()
                with contextlib.suppress(OSError):
                    p.kill()
            t = threading.Timer(timeout, fire)
            t.daemon = True
            t.start()
            return t
        with tempfile.TemporaryFile() as err_log:
            try:
                proc = subprocess.Popen(
                    [sys.executable, "-m", "occsurf.bridge.cli", WORKER_COMMAND],
                    stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err_log, env=_worker_env(),
                    text=True, encoding="utf-8", errors="replace",
                )
            except OSError as err:
                for k in todo:
                    on_report(k, FileReport(path=files[k][0], error=f"cannot start the reader process: {err}"))
                return
            try:
                assert proc.stdin is not None and proc.stdout is not None
                with contextlib.suppress(BrokenPipeError):
                    proc.stdin.write(json.dumps(job))
                    proc.stdin.close()
                for line in proc.stdout:
                    if not line.startswith(_MARK):
                        continue  # stray native output
                    msg = json.loads(line[len(_MARK) :])
                    if "start" in msg:
                        current = todo[msg["start"]]
                        watchdog = arm(proc)
                    elif "report" in msg:
                        if watchdog is not None:
                            watchdog.cancel()
                        k = todo[msg["report"]]
                        done.add(k)
                        current = None
                        on_report(k, FileReport.from_json(msg["data"]))
            finally:
                if watchdog is not None:
                    watchdog.cancel()
                if proc.stdout is not None:
                    proc.stdout.close()
                code = proc.wait()
            detail = _last_line(err_log)
        remaining = [k for k in todo if k not in done]
        if not remaining:
            return
        why = _describe_exit(code)
        if current is None:
            # The worker died outside any file (e.g. cannot import OCC): every file left fails.
            reason = f"the reader process failed ({why})" + (f": {detail}" if detail else "")
            for k in remaining:
                on_report(k, FileReport(path=files[k][0], error=reason))
            return
        if timed_out.is_set():
            error = f"reading this file took longer than {timeout:g} s; the reader process was stopped (--timeout)"
        else:
            error = f"the reader process crashed while reading this file ({why}; a fault inside OpenCascade)"
        on_report(current, FileReport(path=files[current][0], error=error))
        todo = [k for k in remaining if k != current]


# ---------------------------------------------------------------------------------------- output
def _fmt_dev(x: float | None) -> str:
    return "-" if x is None else f"{x:.1e}"


def _fmt_pair(pair: list[int] | None) -> str:
    return "-" if pair is None else f"{pair[0]}x{pair[1]}"


def _fmt_periodic(periodic: list[bool]) -> str:
    return ",".join(d for d, flag in zip("uv", periodic) if flag) or "-"


def _fmt_rational(r: bool | None) -> str:
    return "-" if r is None else ("yes" if r else "no")


_HEADER = ("face", "type", "degree", "poles", "rational", "periodic", "continuity", "max dev", "")
_RIGHT = {0, 7}


def _write_file_table(rep: FileReport, out: TextIO) -> None:
    fmt = f" ({rep.format.upper()})" if rep.format else ""
    out.write(f"{rep.path}{fmt}\n")
    if rep.error is not None:
        out.write(f"  error: {rep.error}\n")
        return
    names = {f.name for f in rep.faces}
    shared_name = names.pop() if len(names) == 1 else None  # one product name on every face: say it once
    if shared_name:
        out.write(f"  name: {shared_name!r}\n")
    rows = [_HEADER]
    for f in rep.faces:
        own = f.name if (f.name and not shared_name) else None
        note = " ".join(x for x in (own and repr(own), f.error and f"[{f.error}]") if x)
        rows.append((str(f.index), f.surface_type, _fmt_pair(f.degree), _fmt_pair(f.poles),
                     _fmt_rational(f.rational), _fmt_periodic(f.periodic), f.continuity or "-",
                     _fmt_dev(f.max_deviation), note))
    widths = [max(len(r[i]) for r in rows) for i in range(len(_HEADER))]
    for r in rows:
        cells = [c.rjust(w) if i in _RIGHT else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))]
        out.write(("  " + "  ".join(cells)).rstrip() + "\n")
    for w in rep.warnings:
        out.write(f"  warning: {w}\n")
    out.write(f"  {len(rep.faces)} faces, {rep.n_free_form} free-form, worst deviation "
              f"{_fmt_dev(rep.worst_deviation)} (relative to bbox diagonal), {rep.seconds:.2f} s\n")


def _cmd_inspect(ns: argparse.Namespace) -> int:
    paths = list(ns.paths)
    if not paths:
        folder = find_samples_dir()
        if folder is None:
            print(f"occsurf: no {SAMPLES_DIR}/ folder found (looked in {Path.cwd() / SAMPLES_DIR} and "
                  "in the installed package); name FILE or DIR arguments", file=sys.stderr)
            return EXIT_ERROR
        paths = [str(folder)]
    t0 = time.perf_counter()
    entries = _expand(paths)
    reports: list[FileReport | None] = [None] * len(entries)
    printed = 0

    def emit(k: int, rep: FileReport) -> None:
        """Store a report; print (stderr line, table) every report that is next in order."""
        nonlocal printed
        reports[k] = rep
        while printed < len(reports) and reports[printed] is not None:
            r = reports[printed]
            assert r is not None
            if r.error is not None:
                print(f"occsurf: {r.path}: {r.error}", file=sys.stderr, flush=True)
            if not ns.json:
                if printed:
                    sys.stdout.write("\n")
                _write_file_table(r, sys.stdout)
                sys.stdout.flush()
            printed += 1

    todo: list[tuple[int, str, Path]] = []
    for k, (shown, path, error) in enumerate(entries):
        if path is None:
            emit(k, FileReport(path=shown, error=error))
        else:
            todo.append((k, shown, path))
    if ns.in_process:
        for k, shown, path in todo:
            emit(k, _inspect_file(shown, path, ns.samples))
    elif todo:
        _inspect_isolated([(shown, path) for _, shown, path in todo], ns.samples, timeout=ns.timeout,
                          on_report=lambda j, rep: emit(todo[j][0], rep))
    done = [r for r in reports if r is not None]
    total = time.perf_counter() - t0
    if ns.json:
        doc = {"samples": ns.samples, "seconds": round(total, 4), "files": [r.to_json() for r in done]}
        sys.stdout.write(json.dumps(doc, indent=1, allow_nan=False) + "\n")
    elif len(done) > 1:
        n_bad = sum(r.error is not None for r in done)
        sys.stdout.write(f"\n{len(done)} files ({n_bad} unreadable), {sum(len(r.faces) for r in done)} faces, "
                         f"{sum(r.n_free_form for r in done)} free-form, {total:.2f} s\n")
    sys.stdout.flush()
    return EXIT_ERROR if any(r.error is not None for r in done) else EXIT_OK


def _fmt_deg(x: float | None) -> str:
    return "-" if x is None else f"{x:.2g} deg"


def _fmt_s(x: float | None) -> str:
    return "-" if x is None else f"{x:.2f} s"


def _cmd_fill(ns: argparse.Namespace) -> int:
    """``occsurf fill IN --out OUT``: fill every hole, print per hole ours vs OCC's filler."""
    src, out = Path(ns.input), Path(ns.out)
    folder = out.parent if str(out.parent) else Path(".")
    if out.is_dir() or not folder.is_dir() or not os.access(folder, os.W_OK):
        why = "is a directory" if out.is_dir() else f"the folder {folder} does not exist or is not writable"
        print(f"occsurf: {out}: cannot write the filled model there ({why})", file=sys.stderr)
        return EXIT_ERROR
    try:
        with warnings.catch_warnings(), _quiet_native_stdout():
            warnings.simplefilter("ignore")
            from ..exchange import step_iges as exchange
            from ..modeling.fill import fill_model

            fmt = _sniff_format(src)
            model = (exchange.read_step if fmt == "step" else exchange.read_iges)(src)
            result = fill_model(model.shape, all_loops=ns.all_loops, compare_occ=not ns.no_occ)
            filled = [h for h in result.holes if h.status == "filled"]
            nothing_to_do = not any(h.status != "outer" for h in result.holes)
            if filled or nothing_to_do:  # a model without holes is written as it is (sewn)
                exchange.write_step(out, result.shape)
    except Exception as err:  # noqa: BLE001 - one line, never a traceback
        print(f"occsurf: {src}: {_strip_path(_one_line(err), src)}", file=sys.stderr)
        return EXIT_ERROR
    holes = [h for h in result.holes if h.status != "outer"]
    failed = [h for h in holes if h.status == "failed"]
    for h in failed:
        print(f"occsurf: {src}: hole {h.index} ({h.sides} sides) not filled: {h.reason}", file=sys.stderr)
    if ns.json:
        from dataclasses import asdict as _asdict

        doc = {"input": str(src), "output": str(out) if filled or nothing_to_do else None,
               "holes": [_asdict(h) for h in result.holes],
               "free_loops_after": result.free_loops_after}
        sys.stdout.write(json.dumps(doc, indent=1) + "\n")
    else:
        n_outer = len(result.holes) - len(holes)
        sys.stdout.write(f"{src}: {len(holes)} holes" + (f" ({n_outer} outer boundaries left open)" if n_outer else "")
                         + "\n")
        rows = [("hole", "sides", "status", "G0 gap", "G1 angle", "time", "OCC G0 gap", "OCC G1 angle", "OCC time")]
        for h in holes:
            occ = ((_fmt_dev(h.occ_g0), _fmt_deg(h.occ_g1), _fmt_s(h.occ_seconds)) if h.occ_status == "ok" else
                   ("failed: " + (h.occ_reason or "?"), "-", _fmt_s(h.occ_seconds)) if h.occ_status else ("-", "-", "-"))
            rows.append((str(h.index), str(h.sides), h.status, _fmt_dev(h.g0), _fmt_deg(h.g1), _fmt_s(h.seconds), *occ))
        widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
        for r in rows:
            sys.stdout.write(("  " + "  ".join(c.ljust(w) for c, w in zip(r, widths))).rstrip() + "\n")
        sys.stdout.write("  (G0 gap in model units, G1 angle between tangent planes: max along the hole's boundary, "
                         "OCC LocalAnalysis_SurfaceContinuity)\n")
        if filled:
            sys.stdout.write(f"wrote {out} ({len(filled)} fills sewn in; {result.free_loops_after} free loops left)\n")
        elif nothing_to_do:
            sys.stdout.write(f"no holes to fill; wrote {out} unchanged\n")
    sys.stdout.flush()
    return EXIT_ERROR if failed or not (filled or nothing_to_do) else EXIT_OK


def _cmd_demo(ns: argparse.Namespace) -> int:
    from occsurf.examples.gallery import run_demos

    return run_demos(Path(ns.out), ns.only)


# ---------------------------------------------------------------------------------------- parser
def _samples_arg(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer from 2 to 1000, got {text!r}") from None
    if not 2 <= n <= 1000:
        raise argparse.ArgumentTypeError(f"expected an integer from 2 to 1000, got {n}")
    return n


def _timeout_arg(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="occsurf",
        description="Spline surfaces of the SIGGRAPH '91 course C25, bridged to OpenCascade.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser(
        "inspect",
        help="list the faces of STEP/IGES files and check our evaluation against OCC's",
        description=("For every face: surface type, degree, poles, rational, periodic, OCC continuity, "
                     "and the largest distance between our evaluation and OCC's on an N x N grid, "
                     "relative to the bounding-box diagonal ('-' for faces that are not B-spline or "
                     "Bezier). Exit status 0 when every file was read, 2 otherwise."),
    )
    p.add_argument("paths", nargs="*", metavar="FILE|DIR",
                   help=f"STEP ({', '.join(STEP_SUFFIXES)}) or IGES ({', '.join(IGES_SUFFIXES)}) files, "
                        f"or folders holding them (default: {SAMPLES_DIR}/)")
    p.add_argument("--json", action="store_true", help="print one JSON document instead of tables")
    p.add_argument("--samples", type=_samples_arg, default=DEFAULT_SAMPLES, metavar="N",
                   help=f"grid size N of the deviation check (default {DEFAULT_SAMPLES})")
    p.add_argument("--timeout", type=_timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop reading a file after this long and report it (default {DEFAULT_TIMEOUT:g})")
    p.add_argument("--in-process", action="store_true",
                   help="read the files in this process, not in a worker (a crash inside OCC then ends it)")
    p.set_defaults(func=_cmd_inspect)

    d = sub.add_parser(
        "demo",
        help="write a gallery of pictures (PNG) and STEP files of what occsurf does",
        description="Renders each chapter's showcase into OUT/<name>/ as PNG pictures plus STEP files.",
    )
    d.add_argument("--out", default="occsurf-demo", metavar="DIR", help="output folder (default: occsurf-demo)")
    d.add_argument("--only", nargs="+", metavar="NAME", help="run only these demos")
    d.set_defaults(func=_cmd_demo)

    f = sub.add_parser(
        "fill",
        help="fill every hole of a STEP/IGES model with G1 patches and compare with OCC's filler",
        description=("Finds the closed loops of free edges of the model's shells (the largest loop of a shell with "
                     "several is its outer boundary and stays open unless --all-loops), fills each hole with n "
                     "G1 patches (course 8-3), sews them in, writes OUT (STEP) and prints per hole: sides, G0 gap "
                     "and G1 angle (OCC LocalAnalysis, max along the boundary) for our fill and for OCC's "
                     "BRepOffsetAPI_MakeFilling. Exit status 0 when every hole was filled, 2 otherwise."),
    )
    f.add_argument("input", metavar="IN", help="STEP or IGES file")
    f.add_argument("--out", required=True, metavar="OUT.step", help="where to write the filled model (STEP)")
    f.add_argument("--all-loops", action="store_true", help="fill outer boundaries too")
    f.add_argument("--no-occ", action="store_true", help="do not run OCC's filler for comparison")
    f.add_argument("--json", action="store_true", help="print one JSON document instead of the table")
    f.set_defaults(func=_cmd_fill)

    w = sub.add_parser(WORKER_COMMAND)  # internal, no help= so it stays out of the listing
    w.set_defaults(func=lambda ns: _worker_main())
    return parser


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
    return int(func(ns))

