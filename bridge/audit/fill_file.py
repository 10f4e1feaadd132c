"""Fill the holes of a STEP/IGES file in worker processes, several at once (``occsurf fill --jobs N``).

:func:`fill_file` is what ``occsurf fill`` runs. The untrusted file is read only in worker
processes (:mod:`occsurf.bridge.isolation`): a crash inside OCC, or a hole that takes longer than
the timeout, costs that worker, never the command.

With one job (or a file with fewer than two holes to fill) one worker reads the file, fills every
hole, sews the fills in once, writes the result and draws the pictures (:func:`fill_job`). With
``jobs`` > 1 the same steps are spread over processes (OCC is not thread-safe, so processes, not
threads):

1. :func:`plan_job` reads the file and counts its holes (free loops, or with ``faces`` the
   edge-connected sets of the faces removed); with fewer than two to fill it does all the work itself;
2. :func:`hole_job` fills hole ``k``, in one of ``jobs`` persistent workers
   (:class:`occsurf.bridge.audit.reader.Reader`, OCC imported and the file read once per worker) fed
   from a thread pool (:class:`concurrent.futures.ThreadPoolExecutor`), a hole at a time, so a long hole
   does not hold up the others. It returns the report and the fill's faces as OCC binary BRep
   (``BinTools``: the doubles as they are);
3. :func:`sew_job` reads the file again, sews every fill in at once, checks, writes ``output`` and
   draws the pictures.

Each hole is filled by the same function on the same model in both paths (:func:`_fill_one`), and
sewn by the same one (:func:`_finish`), so ``jobs`` changes where the work is done, not the faces
written. A worker that crashes or overruns the timeout on a hole makes that hole ``failed`` (with the
reason) and the other holes are still filled and written. The timeout applies per step: the plan,
each hole, the sewing.

Items are the JSON dicts ``{"input", "output", "all_loops", "compare_occ", "faces", "strict",
"pictures"}`` (``faces``: face indices to remove and refill, or empty to fill the free loops); every
job returns the result of :func:`fill_job`: ``{"holes": [per hole dict], "free_loops_after": int or
None, "written": bool, "warnings": [str]}``.
"""

from __future__ import annotations

import base64
import io
import os
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, cast

from ..isolation import CRASHED, ERROR, OK, TIMEOUT, Outcome, run_jobs
from .reader import Reader, on_free_readers

__all__ = ["fill_file", "fill_job", "plan_job", "hole_job", "sew_job", "default_jobs", "PRELOAD", "FILL_JOB"]

#: What a worker imports before its first item (the timeout excludes it).
PRELOAD = ("occsurf.bridge.exchange.step_iges", "occsurf.bridge.modeling.fill")
_HERE = "occsurf.bridge.audit.fill_file"
FILL_JOB, PLAN_JOB, HOLE_JOB, SEW_JOB = (f"{_HERE}:{name}" for name in ("fill_job", "plan_job", "hole_job", "sew_job"))


def default_jobs() -> int:
    """The number of cores this process may run on (``--jobs``'s default)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


# ------------------------------------------------------------------------------------ the model
@dataclass
class _Context:
    """One file read and prepared for filling (a worker keeps the last one: :func:`_context`)."""

    model: Any  # ImportedModel: .shape, .warnings
    holes: Any = None  # ModelHoles (free loops)
    sewn: Any = None  # SewnModel (``faces`` given: refill)
    components: list[list[int]] | None = None  # the faces removed, one set per hole

    @property
    def count(self) -> int:
        return len(self.components) if self.components is not None else len(self.holes.loops)

    def to_fill(self) -> int:
        """Holes that will be filled (not outer boundaries)."""
        return self.count if self.components is not None else sum(not outer for _, outer in self.holes.loops)


_cached: tuple[tuple[Any, ...], _Context] | None = None


def _context(item: dict[str, Any], keep: bool = True) -> _Context:
    """The file of ``item`` read and prepared; with ``keep`` (a worker's steps) kept and reused while
    the file and the options are the same."""
    global _cached
    from ..exchange.reading import read_model

    st = os.stat(item["input"])
    key = (item["input"], st.st_mtime_ns, st.st_size, bool(item.get("strict")), bool(item.get("all_loops")),
           tuple(item.get("faces") or ()))
    if _cached is not None and _cached[0] == key:
        return _cached[1]
    model = read_model(Path(item["input"]), strict=bool(item.get("strict")))
    if item.get("faces"):
        from ..modeling.refill import SewnModel, refill_components

        sewn = SewnModel(model.shape)
        ctx = _Context(model, sewn=sewn, components=refill_components(sewn, list(item["faces"])))
    else:
        from ..modeling.fill import model_holes

        ctx = _Context(model, holes=model_holes(model.shape, bool(item.get("all_loops"))))
    _cached = (key, ctx) if keep else None
    return ctx


def _fill_one(ctx: _Context, k: int, item: dict[str, Any]) -> Any:
    """Hole ``k`` filled and measured: its report, the fill's faces in ``_fill_faces`` when filled."""
    if ctx.components is not None:
        from ..modeling.refill import refill_faces

        return refill_faces(ctx.sewn, ctx.components[k], compare_occ=bool(item["compare_occ"]), check=False,
                            continuity=item.get("continuity", "auto"))[0]
    from ..modeling.fill import fill_loop

    return fill_loop(ctx.holes, k, compare_occ=bool(item["compare_occ"]), continuity=item.get("continuity", "auto"))[0]


def _refill_row(k: int, r: Any) -> dict[str, Any]:
    """A refill report as ``occsurf fill --faces`` prints it (one JSON dict per hole)."""
    d, t = r.occ.get("default", {}), r.occ.get("tuned", {})
    return {"index": k, "faces": r.faces, "sides": r.sides, "g1_edges": r.g1_edges,
            "status": "filled" if r.status == "filled" else "failed", "reason": r.reason,
            "seconds": r.seconds, "g0": r.g0, "g1": r.g1, "side_g0": r.side_g0, "side_g1": r.side_g1,
            "valid": r.valid, "step_round_trip": r.step_round_trip,
            "occ_status": d.get("status"), "occ_reason": d.get("reason"), "occ_seconds": d.get("seconds"),
            "occ_g0": d.get("g0"), "occ_g1": d.get("g1"), "occ_tuned": t or None, "folds": r.folds,
            "method": r.method, "continuity": r.continuity, "original_g2": r.original_g2, "g2_edges": r.g2_edges,
            "g2": r.g2, "side_g2": r.side_g2, "edge_asked": r.edge_asked, "edge_continuity": r.edge_continuity}


def _finish(ctx: _Context, item: dict[str, Any], reports: list[Any]) -> dict[str, Any]:
    """Sew every fill in at once, write ``item["output"]`` (STEP) and the pictures; the job's result."""
    from ..exchange import step_iges
    from ..modeling.fill_pictures import hole_pictures

    out = Path(item["output"])
    if ctx.components is not None:
        from ..modeling.refill import sew_refills

        shape = sew_refills(ctx.sewn, reports)
        written, after = shape is not None, None
        rows = [_refill_row(k, r) for k, r in enumerate(reports)]
    else:
        from ..modeling.fill import sew_fills

        shape, after = sew_fills(ctx.holes, [f for r in reports if r.status == "filled" for f in r._fill_faces])
        filled = any(r.status == "filled" for r in reports)
        written = filled or all(r.status == "outer" for r in reports)  # a model without holes: as it is, sewn
        rows = [asdict(r) for r in reports]
    if written:
        step_iges.write_step(out, shape)
        if item.get("pictures", True):
            hole_pictures(out, reports, rows, refill=ctx.components is not None)
    return {"holes": rows, "free_loops_after": after, "written": written, "warnings": list(ctx.model.warnings)}


def _quietly(func: Any) -> Any:
    """Run a job with OCC's and Python's chatter off (the worker's stdout carries the protocol)."""
    from functools import wraps

    @wraps(func)
    def job(item: dict[str, Any]) -> Any:
        from ..isolation import quiet_native_stdout

        with warnings.catch_warnings(), quiet_native_stdout():
            warnings.simplefilter("ignore")
            return func(item)

    return job


# ------------------------------------------------------------------------------------ the jobs
@_quietly
def fill_job(item: dict[str, Any]) -> dict[str, Any]:
    """Read ``item["input"]``, fill every hole, sew them in once, write ``item["output"]`` (one process).

    The output is written when some hole was filled, or (free loops) when there was none to fill:
    the model as it is, sewn.

    Raises
    ------
    Exception
        Whatever reading, filling or writing raises (the command prints it on one line).
    """
    ctx = _context(item, keep=False)  # one shot (and maybe in the caller's process: nothing kept)
    return _finish(ctx, item, [_fill_one(ctx, k, item) for k in range(ctx.count)])


@_quietly
def plan_job(item: dict[str, Any]) -> dict[str, Any]:
    """How many holes the file has: ``{"holes": n, "sides": [...]}``; or, with fewer than two to
    fill, the whole work done here: ``{"done": <fill_job's result>}``."""
    ctx = _context(item)
    if ctx.to_fill() < 2:
        return {"done": _finish(ctx, item, [_fill_one(ctx, k, item) for k in range(ctx.count)])}
    sides = None if ctx.holes is None else [len(edges) for edges, _ in ctx.holes.loops]
    return {"holes": ctx.count, "sides": sides, "components": ctx.components}


@_quietly
def hole_job(item: dict[str, Any]) -> dict[str, Any]:
    """Fill hole ``item["hole"]``: ``{"report": dict, "faces": base64 BinTools compound or None,
    "pid": the worker's process id}``."""
    ctx = _context(item)
    rep = _fill_one(ctx, int(item["hole"]), item)
    faces = getattr(rep, "_fill_faces", None) if rep.status == "filled" else None
    return {"report": asdict(rep),
            "faces": None if faces is None else _faces_to_text(faces), "pid": os.getpid()}


@_quietly
def sew_job(item: dict[str, Any]) -> dict[str, Any]:
    """Sew the fills of :func:`hole_job` (``item["results"]``, in hole order) into the file's model
    once, write ``item["output"]`` and draw the pictures; :func:`fill_job`'s result."""
    ctx = _context(item)
    reports = [_report(ctx, k, res) for k, res in enumerate(item["results"])]
    return _finish(ctx, item, reports)


def _report(ctx: _Context, k: int, res: dict[str, Any]) -> Any:
    """A report of :func:`hole_job` again, with the faces and the objects the pictures draw."""
    if ctx.components is not None:
        from ..modeling.joints import unique_faces
        from ..modeling.refill import RefillReport
        from ..modeling.refill_loop import hole_loop

        rep: Any = RefillReport(**res["report"])
        if res.get("faces") is not None:
            rep._fill_faces = _faces_from_text(res["faces"])
            rep._removed = [ctx.sewn.faces[i] for i in rep.faces]
            rep._neighbours = unique_faces(hole_loop(ctx.sewn, rep.faces)[1])
        return rep
    from ..modeling.fill import HoleReport, hole_neighbours

    rep = HoleReport(**res["report"])
    if res.get("faces") is not None:
        rep._fill_faces = _faces_from_text(res["faces"])
        rep._neighbours = hole_neighbours(ctx.holes, k)
    return rep


def _faces_to_text(faces: list[Any]) -> str:
    """Faces as one compound in OCC's binary BRep format, base64 (exact: the doubles as stored)."""
    from OCP.BinTools import BinTools
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    comp, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(comp)
    for f in faces:
        builder.Add(comp, f)
    buf = io.BytesIO()
    BinTools.Write_s(comp, buf)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _faces_from_text(text: str) -> list[Any]:
    """The faces of :func:`_faces_to_text`, in their order."""
    from OCP.BinTools import BinTools
    from OCP.TopoDS import TopoDS, TopoDS_Iterator, TopoDS_Shape

    shape = TopoDS_Shape()
    BinTools.Read_s(shape, io.BytesIO(base64.b64decode(text)))
    out, it = [], TopoDS_Iterator(shape)
    while it.More():
        out.append(TopoDS.Face_s(it.Value()))
        it.Next()
    return out


# ------------------------------------------------------------------------------------ the driver
def fill_file(item: dict[str, Any], *, jobs: int = 1, timeout: float | None = None,
              isolate: bool = True) -> Outcome:
    """Fill every hole of ``item["input"]`` and write ``item["output"]``, in worker processes.

    Parameters
    ----------
    item : dict
        ``{"input": str, "output": str, "all_loops": bool, "compare_occ": bool, "faces": [int],
        "strict": bool, "pictures": bool}`` (see the module).
    jobs : int, default 1
        Worker processes filling holes at once (:func:`default_jobs`: one per core). 1: everything
        in one worker.
    timeout : float, optional
        Seconds a step may take before its worker is stopped: the whole fill with one job; with
        several, the plan, each hole (that hole then fails, the others go on) and the sewing.
    isolate : bool, default True
        ``False``: all in this process, one hole after the other (no protection; ``jobs`` ignored).

    Returns
    -------
    Outcome
        ``value`` is :func:`fill_job`'s result when ``ok``; otherwise why there is none (as
        :func:`occsurf.bridge.isolation.run_jobs` reports it).

    Raises
    ------
    ValueError
        ``jobs`` not a positive integer.
    """
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs: expected a positive number of worker processes, got {jobs!r}")
    if jobs == 1 or not isolate:
        [outcome] = run_jobs(FILL_JOB, [item], timeout=timeout, isolate=isolate, preload=PRELOAD)
        return outcome
    first = Reader(PRELOAD)  # plans, fills holes and sews: the file read once there
    readers = [first]
    try:
        plan = _outcome(first, PLAN_JOB, item, timeout)
        if not plan.ok or "done" in plan.value:
            return plan if not plan.ok else Outcome(0, OK, value=plan.value["done"], seconds=plan.seconds)
        readers += [Reader(PRELOAD) for _ in range(min(jobs, int(plan.value["holes"])) - 1)]
        results = _fill_holes(item, plan.value, readers, timeout)
        return _outcome(first, SEW_JOB, {**item, "results": results}, timeout)
    finally:
        for r in readers:
            r.stop()


def _outcome(reader: Reader, job: str, item: dict[str, Any], timeout: float | None) -> Outcome:
    """``job`` run on ``item`` by ``reader``, as :func:`run_jobs` would report it."""
    return reader.outcome(job, item, timeout)


def _fill_holes(item: dict[str, Any], plan: dict[str, Any], workers: list[Reader],
                timeout: float | None) -> list[dict[str, Any]]:
    """Every hole of the plan through :func:`hole_job`, one per worker at a time; results in hole order."""

    def fill(reader: Reader, k: int) -> dict[str, Any]:
        outcome = _outcome(reader, HOLE_JOB, {**item, "hole": k}, timeout)
        if outcome.ok:
            return cast(dict[str, Any], outcome.value)
        return {"report": _failed_report(plan, k, _hole_failure(outcome, timeout)), "faces": None}

    def stopped(k: int) -> dict[str, Any]:
        return {"report": _failed_report(plan, k, "interrupted"), "faces": None}

    return on_free_readers(workers, int(plan["holes"]), fill, stopped, name="fill")


def _hole_failure(outcome: Outcome, timeout: float | None) -> str:
    if outcome.status == TIMEOUT:
        return f"filling this hole took longer than {timeout:g} s; its worker process was stopped (--timeout)"
    if outcome.status == CRASHED:
        return f"the worker process crashed while filling this hole ({outcome.exit_reason or outcome.error}; a fault inside OpenCascade)"
    if outcome.status == ERROR:
        return outcome.error or "unknown error"
    return f"no worker process to fill this hole: {outcome.error}"


def _failed_report(plan: dict[str, Any], k: int, reason: str) -> dict[str, Any]:
    """The report fields of a hole whose worker gave no result."""
    if plan.get("components") is not None:
        return {"faces": plan["components"][k], "status": "failed", "reason": reason}
    return {"index": k, "sides": plan["sides"][k], "status": "failed", "reason": reason}
