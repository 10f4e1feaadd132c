"""STEP exchange of hierarchical splines (course §5-17): flat geometry + an editable sidecar.

STEP has no entity for a Forsey–Bartels hierarchy, so :func:`write_hierarchical_step` writes

* the STEP file: the exact flat form (:meth:`HierarchicalSurface.flatten`, one B-spline face; a
  hierarchical curve becomes one edge) that every CAD system reads, through
  :func:`occsurf.bridge.exchange.step_iges.write_step` (17 significant digits: bit-exact poles);
* a JSON *sidecar* beside it (``model.step`` -> ``model.hierarchy.json``): the hierarchy's
  :meth:`~HierarchicalSurface.to_dict` plus a fingerprint of the STEP file it belongs to.

Both are written together (:func:`occsurf.bridge.exchange.files.atomic_write_many`): each to a synced
temporary file beside its target, and only when both are complete are they renamed over the targets,
under an exclusive ``flock`` of their folder that readers take shared: two
processes writing the same pair never leave the STEP file of one with the sidecar of the other. A
failed write leaves no file behind and the old pair untouched.
:func:`read_hierarchical_step` restores the editable hierarchy from the sidecar and checks that
the STEP geometry still equals its flat form (a STEP file edited elsewhere, or a stale sidecar,
raises :class:`ExchangeError` instead of silently loading details onto the wrong surface).
:func:`import_step_base` turns a B-spline face of any STEP file into the base of a new hierarchy.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError
from occsurf.algorithms.hierarchical.curve import HierarchicalCurve
from occsurf.algorithms.hierarchical.offsets import OffsetMapping
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface

from . import files as _files
from . import occ_io as _xocc
from .step_iges import STEP_DIGITS, read_step

__all__ = ["SIDECAR_SUFFIX", "SIDECAR_MATCH_RTOL", "sidecar_path", "write_hierarchical_step",
           "read_hierarchical_step", "import_step_base"]

#: The sidecar of ``name.step`` is ``name`` + this suffix.
SIDECAR_SUFFIX: str = ".hierarchy.json"

#: The STEP geometry must equal the sidecar's flat form to this relative tolerance (of the
#: model's size) at the check samples. The STEP write is bit-exact, so a real match is ~1e-16;
#: anything above 1e-9 means the two files do not belong together.
SIDECAR_MATCH_RTOL: float = 1e-9

_SIDECAR_FORMAT = "occsurf-hierarchy-sidecar"
_SIDECAR_VERSION = 1
_CLASSES: dict[str, type[HierarchicalSurface] | type[HierarchicalCurve]] = {
    "HierarchicalSurface": HierarchicalSurface, "HierarchicalCurve": HierarchicalCurve}


def sidecar_path(step_path: str | os.PathLike[str]) -> Path:
    """``model.step`` -> ``model.hierarchy.json`` (same folder)."""
    p = Path(os.fsdecode(step_path))
    return p.with_name(p.stem + SIDECAR_SUFFIX)


def write_hierarchical_step(path: str | os.PathLike[str], hierarchy: HierarchicalSurface | HierarchicalCurve,
                            name: str | None = None, *, replace_readonly: bool = False,
                            sidecar: str | os.PathLike[str] | None = None) -> tuple[Path, Path]:
    """Write the flat form to STEP and the hierarchy to a JSON sidecar, both atomically.

    Parameters
    ----------
    path : str or path-like
        The STEP file.
    hierarchy : HierarchicalSurface or HierarchicalCurve
        3-D.
    name : str, optional
        Product/face name in the STEP file.
    replace_readonly : bool
        Replace a read-only STEP file or sidecar (refused by default).
    sidecar : str or path-like, optional
        Where the sidecar goes instead of :func:`sidecar_path` (``occsurf fit`` writes ``OUT.json``);
        :func:`read_hierarchical_step` then needs the same ``sidecar=``.

    Returns
    -------
    (Path, Path)
        The STEP file and the sidecar.

    Raises
    ------
    InvalidGeometryError
        Not a hierarchy, or not 3-D.
    ExchangeError, KernelError
        As :func:`occsurf.bridge.exchange.step_iges.write_step` (an unwritable path or sidecar path); no file is
        created or modified then.
    """
    if not isinstance(hierarchy, (HierarchicalSurface, HierarchicalCurve)):
        raise InvalidGeometryError(f"hierarchy: expected a HierarchicalSurface or HierarchicalCurve, got "
                                   f"{type(hierarchy).__name__}")
    step = _files.target(path, replace_readonly=replace_readonly)
    side = sidecar_path(step) if sidecar is None else Path(os.fsdecode(sidecar))
    if side.is_dir():
        raise ExchangeError(f"{side}: is a directory; cannot write the hierarchy sidecar there")
    _files.check_target(side, replace_readonly=replace_readonly)
    flat = hierarchy.flatten()
    # The STEP bytes exactly as occsurf.bridge.exchange.step_iges.write_step makes them, kept in memory so that the
    # pair is committed together: nothing on disk changes until both files are complete.
    step_data = _xocc.step_bytes(step, _xocc.normalise(flat, name), STEP_DIGITS)
    data = {
        "format": _SIDECAR_FORMAT,
        "version": _SIDECAR_VERSION,
        "step_file": step.name,
        "step_sha256": hashlib.sha256(step_data).hexdigest(),
        "pole_counts": hierarchy.pole_counts(),
        "hierarchy": hierarchy.to_dict(),
    }
    with _files.file_lock(_lock_path(side)):  # the pair is one unit for concurrent writers and readers
        other = _sidecar_owner(side)
        if other is not None and other != step.name and (step.parent / other).exists():
            raise ExchangeError(f"{side}: is the hierarchy sidecar of {other}, which would lose it; write "
                                f"{step.name} under another name (model.step and model.stp share one sidecar name)")
        _files.atomic_write_many([(step, step_data), (side, (json.dumps(data, indent=1) + "\n").encode())],
                                 replace_readonly=replace_readonly)
    return step, side


def _lock_path(side: Path) -> Path:
    """What locks a STEP + sidecar pair: their folder (``flock`` on the directory; no lock file is left)."""
    return side.parent if str(side.parent) else Path(".")


def _sidecar_owner(side: Path) -> str | None:
    """The ``step_file`` an existing sidecar names, or None (no file, or not one of ours)."""
    try:
        data = json.loads(side.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return None
    owner = data.get("step_file") if isinstance(data, dict) and data.get("format") == _SIDECAR_FORMAT else None
    return owner if isinstance(owner, str) else None


def _check_params(knots: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Every distinct knot of the flat form in ``[lo, hi]`` and 1/4, 1/2, 3/4 of every span: each
    polynomial piece is sampled, however small the finest overlay is."""
    k = np.unique(np.clip(knots, lo, hi))
    inner = [k[:-1] + f * np.diff(k) for f in (0.25, 0.5, 0.75)]
    return np.unique(np.concatenate([k] + inner))


def _samples(obj: Any, params: tuple[np.ndarray, ...]) -> np.ndarray:
    if isinstance(obj, (HierarchicalSurface, BSplineSurface)):
        return obj.evaluate_grid(*params)
    return obj.evaluate(params[0])


def read_hierarchical_step(path: str | os.PathLike[str], *, sidecar: str | os.PathLike[str] | None = None,
                           isolated: bool = False, timeout: float | None = None
                           ) -> HierarchicalSurface | HierarchicalCurve:
    """Restore the editable hierarchy written by :func:`write_hierarchical_step`.

    The sidecar must name this STEP file, and the file must be the one written with it (its SHA-256
    is stored) or, if it was saved again, its first face (or free edge, for a curve) must equal the
    sidecar hierarchy's flat form within :data:`SIDECAR_MATCH_RTOL` at every distinct knot and at
    three points inside every knot span of the flat form.

    Parameters
    ----------
    path : str or path-like
        The STEP file.
    sidecar : str or path-like, optional
        The sidecar's path when it was written elsewhere than :func:`sidecar_path`.
    isolated : bool, default False
        Parse the STEP file (needed only when it is not byte for byte the one written with the sidecar)
        in a worker process, as :func:`occsurf.bridge.exchange.step_iges.read_step` does: a crash or a
        hang inside OCC becomes an :class:`ExchangeError` naming the file. Use it for files from
        untrusted sources.
    timeout : float, optional
        With ``isolated``: seconds the worker may take (default no limit).

    Raises
    ------
    ExchangeError
        No sidecar, an unreadable or foreign sidecar, a sidecar of another STEP file (``model.stp``
        beside ``model.step``), or a STEP file whose geometry no longer matches it (edited after
        writing); with ``isolated``, a crash or time-out of the reader process. Messages name the path.
    InvalidGeometryError
        ``timeout`` not a positive number of seconds.
    """
    p = Path(os.fsdecode(path))
    side = sidecar_path(p) if sidecar is None else Path(os.fsdecode(sidecar))
    _check_timeout(timeout)
    with _files.file_lock(_lock_path(side), shared=True):
        return _read_pair(p, side, isolated, timeout)


def _check_timeout(timeout: Any) -> None:
    """``timeout``: None or a positive, finite number of seconds (checked before any file is read)."""
    if timeout is None:
        return
    number = isinstance(timeout, (int, float)) and not isinstance(timeout, bool)
    if not (number and np.isfinite(timeout) and timeout > 0):
        raise InvalidGeometryError(f"timeout: expected a positive number of seconds or None, got {timeout!r}")
    from ..isolation import MAX_TIMEOUT

    if timeout > MAX_TIMEOUT:
        raise InvalidGeometryError(f"timeout: at most {MAX_TIMEOUT:g} seconds, got {timeout!r}")


def _read_pair(p: Path, side: Path, isolated: bool = False,
               timeout: float | None = None) -> HierarchicalSurface | HierarchicalCurve:
    if not side.is_file():
        raise ExchangeError(f"{side}: no hierarchy sidecar beside {p.name}; use import_step_base() to start a new "
                            "hierarchy from the STEP geometry")
    try:
        data = json.loads(side.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ExchangeError(f"{side}: unreadable hierarchy sidecar: {err}") from err
    if not isinstance(data, dict) or data.get("format") != _SIDECAR_FORMAT:
        raise ExchangeError(f"{side}: not an occsurf hierarchy sidecar")
    version = data.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or not 1 <= version <= _SIDECAR_VERSION:
        raise ExchangeError(f"{side}: sidecar version {version!r} is not supported (this is version "
                            f"{_SIDECAR_VERSION}; older versions load)")
    owner = data.get("step_file")
    if isinstance(owner, str) and owner != p.name:
        raise ExchangeError(f"{side}: the hierarchy sidecar of {owner}, not of {p.name}")
    d = data.get("hierarchy")
    kind = d.get("type") if isinstance(d, dict) else None
    cls = _CLASSES.get(kind) if isinstance(kind, str) else None
    if cls is None or not isinstance(d, dict):
        raise ExchangeError(f"{side}: the sidecar holds no hierarchical surface or curve")
    try:
        h = cls.from_dict(d)
    except (InvalidGeometryError, TypeError, KeyError, IndexError) as err:  # any malformed content
        raise ExchangeError(f"{side}: invalid hierarchy: {err}") from err
    try:
        same = hashlib.sha256(p.read_bytes()).hexdigest() == data.get("step_sha256")
    except OSError:
        same = False  # read_step names the problem
    if same:
        return h  # the very file written with this sidecar: no need to parse it
    model = read_step(p, isolated=isolated, timeout=timeout)
    geo: BSplineSurface | BSplineCurve | None
    if cls is HierarchicalSurface:
        geo = model.faces[0].surface if model.faces else None
    else:
        geo = model.edges[0].curve if model.edges else None
    if geo is None:
        raise ExchangeError(f"{p}: no {'face' if cls is HierarchicalSurface else 'edge'} to match the sidecar")
    # Re-saved or edited: the geometry must still be the hierarchy's, on every polynomial piece.
    flat = h.flatten()
    if isinstance(flat, BSplineSurface):
        params = tuple(_check_params(flat.knots[i], *flat.domain[i]) for i in range(2))
    else:
        params = (_check_params(flat.knots, *flat.domain),)
    ours = _samples(h, params)
    try:
        theirs = _samples(geo, params)
    except InvalidGeometryError as err:
        raise ExchangeError(f"{p}: its geometry does not match the sidecar ({err})") from err
    scale = max(1.0, float(np.abs(ours).max()))
    dev = float(np.abs(ours - theirs).max()) if ours.shape == theirs.shape else np.inf
    if not dev <= SIDECAR_MATCH_RTOL * scale:
        raise ExchangeError(f"{p}: the STEP geometry differs from the hierarchy in {side.name} by {dev:.3g} "
                            "(edited after writing, or a stale sidecar)")
    return h


def import_step_base(path: str | os.PathLike[str], face: int = 0,
                     offsets: str | OffsetMapping = "frame", *, isolated: bool = False,
                     timeout: float | None = None) -> HierarchicalSurface:
    """A new hierarchy whose base is a B-spline face of a STEP file (exact conversion).

    Parameters
    ----------
    path : str or path-like
    face : int
        Index into :attr:`occsurf.bridge.exchange.step_iges.ImportedModel.faces`.
    offsets : {"frame", "additive"} or OffsetMapping
    isolated : bool, default False
        Parse the file in a worker process (:func:`occsurf.bridge.exchange.step_iges.read_step`): a crash
        or a hang inside OCC becomes an :class:`ExchangeError` naming the file. The face comes back
        bit-exact. Use it for files from untrusted sources.
    timeout : float, optional
        With ``isolated``: seconds the worker may take (default no limit).

    Raises
    ------
    ExchangeError
        Unreadable file, no such face, or a face that is not a B-spline surface (its type named); with
        ``isolated``, a crash or time-out of the reader process.
    InvalidGeometryError
        ``timeout`` not a positive number of seconds.
    """
    _check_timeout(timeout)
    model = read_step(path, isolated=isolated, timeout=timeout)
    if isinstance(face, bool) or not isinstance(face, int) or not 0 <= face < len(model.faces):
        raise ExchangeError(f"{model.path}: face index {face!r} is not in 0..{len(model.faces) - 1}")
    f = model.faces[face]
    if f.surface_type not in ("BSplineSurface", "BezierSurface") or f.surface is None:
        raise ExchangeError(f"{model.path}: face {face} is a {f.surface_type}, not a B-spline surface"
                            + (f" ({f.error})" if f.error else ""))
    return HierarchicalSurface(f.surface, offsets)
