"""Match two faces of a STEP/IGES file, or repair a model, in a worker process (``occsurf match``,
``occsurf repair``).

:func:`match_file` is what ``occsurf match`` runs: the untrusted file is read in a worker
(:mod:`occsurf.bridge.isolation`), :func:`occsurf.bridge.modeling.matching.match_faces` changes
the face, and the result is written to STEP (atomically: :func:`~occsurf.bridge.exchange.step_iges.
write_step`) only when the tolerances are met and ``BRepCheck_Analyzer`` finds the model valid.

Items are the JSON dicts ``{"input", "output", "face", "target", "continuity",
"preserve_opposite", "average", "tol_g0", "tol_g1_deg", "tol_g2_rel", "sharp_deg", "strict"}``;
the job returns ``{"report": FaceMatch.to_dict(), "written": bool, "refused": str or None,
"warnings": [str]}``.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

from ..isolation import Outcome, run_jobs

__all__ = ["match_file", "match_job", "repair_job", "MATCH_JOB", "REPAIR_JOB", "PRELOAD"]

#: What a worker imports before its first item (the timeout excludes it).
PRELOAD = ("occsurf.bridge.exchange.step_iges", "occsurf.bridge.modeling.matching")
MATCH_JOB = "occsurf.bridge.audit.match_file:match_job"
REPAIR_JOB = "occsurf.bridge.audit.match_file:repair_job"


def _refusal(rep: dict[str, Any], item: dict[str, Any]) -> str | None:
    """Why the matched model is not written (``None``: it is)."""
    if not rep["valid"]:
        return "the changed model is not valid for BRepCheck_Analyzer; nothing written"
    if not rep["met"]:
        return (f"the tolerances are not met after {rep['knots_added']} knots (G0 {rep['g0_max']:.3g}, "
                f"G1 {rep['g1_max_deg']:.3g} deg, G2 {rep['g2_max_rel']:.3g}); nothing written")
    return None


def match_job(item: dict[str, Any]) -> dict[str, Any]:
    """Read ``item["input"]``, match the faces, write ``item["output"]`` when the result holds."""
    from ..exchange import step_iges
    from ..exchange.reading import read_model
    from ..isolation import quiet_native_stdout
    from ..modeling.matching import MATCH_SHARP_DEG, match_faces

    with warnings.catch_warnings(), quiet_native_stdout():
        warnings.simplefilter("ignore")
        model = read_model(Path(item["input"]), strict=bool(item.get("strict")))
        report, shape = match_faces(
            model.shape, int(item["face"]), int(item["target"]), str(item.get("continuity", "G1")),
            preserve_opposite=str(item.get("preserve_opposite", "G1")), average=bool(item.get("average")),
            tol_g0=item.get("tol_g0"), tol_g1_deg=float(item.get("tol_g1_deg", 0.01)),
            tol_g2_rel=float(item.get("tol_g2_rel", 0.01)),
            sharp_deg=float(item.get("sharp_deg") or MATCH_SHARP_DEG))
        rep = report.to_dict()
        why = _refusal(rep, item)
        if why is None:
            step_iges.write_step(item["output"], shape)
    return {"report": rep, "written": why is None, "refused": why, "warnings": list(model.warnings)}


def repair_job(item: dict[str, Any]) -> dict[str, Any]:
    """Read ``item["input"]``, repair it with ``item["preset"]`` (``item["max_change"]``), write
    ``item["output"]`` and the page ``<output stem>_report/index.html``, read the written file
    again: ``{"report": dict (with ``round_trip``: faces in, faces read back, BRepCheck validity of
    what was read), "page": str, "warnings": [str]}``."""
    from ..exchange import step_iges
    from ..exchange.reading import read_model
    from ..isolation import quiet_native_stdout
    from .repair import repair_model, write_repair_page

    with warnings.catch_warnings(), quiet_native_stdout():
        warnings.simplefilter("ignore")
        model = read_model(Path(item["input"]), strict=bool(item.get("strict")))
        report, shape = repair_model(model.shape, str(item.get("preset", "catia")), max_change=item.get("max_change"))
        out = Path(item["output"])
        step_iges.write_step(out, shape)
        page = write_repair_page(report, out.with_name(out.stem + "_report"), Path(item["input"]).name)
        back = read_model(out)  # the written file read again: faces and validity, as OCC sees them
        from OCP.BRepCheck import BRepCheck_Analyzer

        from ..modeling.refill_loop import model_faces

        round_trip = {"faces_in": len(model_faces(model.shape)), "faces_out": len(model_faces(back.shape)),
                      "valid": bool(BRepCheck_Analyzer(back.shape).IsValid())}
    return {"report": {**report.to_dict(), "round_trip": round_trip}, "page": str(page),
            "warnings": list(model.warnings)}


def match_file(item: dict[str, Any], *, timeout: float | None = None, isolate: bool = True,
               job: str = MATCH_JOB) -> Outcome:
    """:func:`match_job` (or ``job``: :data:`REPAIR_JOB`) on ``item`` in a worker process
    (``isolate=False``: in this one)."""
    [outcome] = run_jobs(job, [item], timeout=timeout, isolate=isolate, preload=PRELOAD)
    return outcome
