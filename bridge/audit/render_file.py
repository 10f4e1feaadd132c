"""Render a STEP/IGES file under Warn's lights in a worker process (``occsurf render``): the job.

:func:`render_job` validates the lights, reads the model, meshes and renders it
(:mod:`occsurf.bridge.rendering.lighting`) and writes the PNG, in a worker process
(:mod:`occsurf.bridge.isolation`): a crash inside OCC or VTK costs the worker, not the command.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

from ..exchange.reading import read_model

__all__ = ["render_job", "RENDER_JOB", "PRELOAD"]

#: The job, as the worker imports it, and what the worker loads before its first item.
RENDER_JOB = "occsurf.bridge.audit.render_file:render_job"
PRELOAD = ("occsurf.bridge.exchange.step_iges", "occsurf.bridge.rendering.lighting")


def render_job(item: dict[str, Any]) -> dict[str, Any]:
    """The worker's job: validate the lights, read ``item["input"]``, render, write ``item["output"]``.

    Parameters
    ----------
    item : dict
        ``{"input", "output", "lights": dict or None, "preset": str or None, "size": [w, h],
        "view": str, "camera": {"position", "target" or None, "up"} or None}``.

    Returns
    -------
    dict
        ``{"faces", "triangles", "lights", "size", "render_seconds"}``.
    """
    import numpy as np

    from occsurf.algorithms.lighting import preset, setup_from_dict

    from ..exchange.files import check_target
    from ..isolation import quiet_native_stdout
    from ..rendering.lighting import Camera, camera_for_view, mesh_of_model, render_lit, write_png

    # fail before reading the model: the lights, then the target (again: it may have changed)
    setup = setup_from_dict(item["lights"]) if item.get("lights") is not None else None
    check_target(item["output"])
    with warnings.catch_warnings(), np.errstate(all="ignore"), quiet_native_stdout():
        warnings.simplefilter("ignore")
        model = read_model(Path(item["input"]), strict=bool(item.get("strict")))
        P, T, N = mesh_of_model(model)
    lo, hi = P.min(axis=0), P.max(axis=0)
    centre, diag = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) or 1.0
    if setup is None:
        setup = preset(item["preset"], centre, diag)
    width, height = item["size"]
    cam = item.get("camera")
    if cam is not None:
        camera = Camera(position=cam["position"], target=cam["target"] if cam.get("target") else tuple(centre),
                        up=cam.get("up") or (0.0, 0.0, 1.0))
    else:
        camera = camera_for_view(item["view"], lo, hi, width / height)
    image = render_lit(P, T, setup, normals=N, size=(width, height), camera=camera, samples=item.get("samples", 4))
    write_png(item["output"], image)
    return {"faces": len(model.faces), "triangles": int(len(T)), "lights": len(setup.lights), "size": [width, height],
            "render_seconds": round(image.seconds, 4), "warnings": list(model.warnings)}
