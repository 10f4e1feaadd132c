"""Fit a data file in a worker process (``occsurf fit``): the job the command runs.

:func:`fit_job` reads the data (a point table, a STEP/IGES face, ...; :mod:`occsurf.bridge.modeling.fit`),
fits it and writes the outputs, in a worker process (:mod:`occsurf.bridge.isolation`), so a file
that crashes OCC costs the worker, not the command. Its progress lines go to a file the command
follows.
"""

from __future__ import annotations

from typing import Any

__all__ = ["fit_job", "FIT_JOB", "PRELOAD"]

#: The job, as the worker imports it, and what the worker loads before its first item.
FIT_JOB = "occsurf.bridge.audit.fit_file:fit_job"
PRELOAD = ("occsurf.bridge.modeling.fit",)


def fit_job(item: dict[str, Any]) -> dict[str, Any]:
    """The worker's job: read ``item["input"]``, fit, write the outputs; returns the JSON report.

    ``item`` holds the command's options (``tol``, ``ctrl``, ``degree``, ``smooth``,
    ``fix_boundary``, ``x``, ``y``, ``face``, ``levels``), ``output`` and ``progress`` (a file the
    job appends its progress lines to, or None).
    """
    import warnings

    from ..isolation import quiet_native_stdout

    log = open(item["progress"], "a", encoding="utf-8") if item.get("progress") else None  # noqa: SIM115

    def say(msg: str) -> None:
        if log is not None:
            log.write(msg + "\n")
            log.flush()

    try:
        with warnings.catch_warnings(), quiet_native_stdout():
            warnings.simplefilter("ignore")
            from ..modeling.fit import fit_input, read_fit_input, write_fit_outputs

            inp = read_fit_input(item["input"], face=item.get("face"), x_range=item.get("x"), y_range=item.get("y"),
                                 strict=bool(item.get("strict")))
            say(inp.description)
            res = fit_input(inp, item["tol"], ctrl=item.get("ctrl"), degree=item["degree"], smooth=item["smooth"],
                            fix_boundary=item["fix_boundary"], max_levels=item.get("levels"), progress=say)
            say("writing " + item["output"])
            outputs = write_fit_outputs(res, item["output"])
    finally:
        if log is not None:
            log.close()
    doc = {"input": item["input"], "detected": inp.description, "kind": inp.kind, "warnings": list(inp.warnings)}
    doc.update(res.report())
    doc["outputs"] = outputs
    return doc
