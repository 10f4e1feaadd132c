"""The results of an audit on disk: two Parquet datasets written incrementally, resumable.

::

    RESULTS/files/part-<run>-<seq>.parquet    one row per input file (FILES_SCHEMA)
    RESULTS/faces/part-<run>-<seq>.parquet    one row per face (FACES_SCHEMA), keyed by sha256

Rows are buffered for at most ``flush_seconds`` (or ``flush_rows`` files) and then written as a
new part file through occsurf's one atomic-write helper (:func:`occsurf.bridge.exchange.files.atomic_write`):
to a hidden, locked temporary name in the same folder, synced, then renamed (:func:`os.replace`, atomic);
the temporary file of a killed run is removed by the next write to that folder. Parquet readers skip
names starting with ``.`` (and only ``part-*.parquet`` is read here), so
``pyarrow.dataset.dataset(RESULTS / "files")`` reads a consistent table at every moment, even
while an audit runs or after it was killed. A batch's faces part is renamed before its files
part: a file counts as audited once its files row exists, and ``--resume`` deletes a faces part
whose files part never appeared (the run was killed between the two renames), so no face is
stored twice.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
import uuid
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.dataset as ds
import pyarrow.parquet as pq

from occsurf.algorithms.errors import ExchangeError

from ..exchange import files as _files

__all__ = ["FILES_SCHEMA", "FACES_SCHEMA", "ResultStore", "StoreError", "read_files", "read_faces"]

FILES_SCHEMA = pa.schema([
    ("path", pa.string()), ("sha256", pa.string()), ("size", pa.int64()), ("format", pa.string()),
    ("status", pa.string()), ("error", pa.string()), ("signal", pa.string()), ("exit_code", pa.int32()),
    ("n_faces", pa.int32()), ("n_free_form", pa.int32()), ("max_dev", pa.float64()),
    ("roundtrip_status", pa.string()), ("roundtrip_max_dev", pa.float64()), ("roundtrip_inexact", pa.int32()),
    ("quality_status", pa.string()), ("quality_worst_g1_deg", pa.float64()),
    ("quality_curvature_spikes", pa.int32()), ("quality_flags", pa.string()),
    ("seconds", pa.float64()), ("worker", pa.string()), ("run_id", pa.string()),
    ("finished", pa.timestamp("ms", tz="UTC")),
])

FACES_SCHEMA = pa.schema([
    ("sha256", pa.string()), ("face", pa.int32()), ("name", pa.string()), ("type", pa.string()),
    ("degree_u", pa.int32()), ("degree_v", pa.int32()), ("poles_u", pa.int32()), ("poles_v", pa.int32()),
    ("rational", pa.bool_()), ("periodic_u", pa.bool_()), ("periodic_v", pa.bool_()),
    ("continuity", pa.string()), ("max_dev", pa.float64()), ("max_d1_dev", pa.float64()),
    ("max_d2_dev", pa.float64()), ("max_normal_angle", pa.float64()), ("roundtrip_dev", pa.float64()),
    ("roundtrip_exact", pa.bool_()), ("error", pa.string()),
])


class StoreError(OSError):
    """RESULTS cannot be created or written, or already holds results without ``--resume``."""


def _table(rows: list[dict[str, Any]], schema: pa.Schema) -> pa.Table:
    return pa.Table.from_pylist([{f.name: r.get(f.name) for f in schema} for r in rows], schema=schema)


def _dataset_table(folder: Path, schema: pa.Schema, columns: list[str] | None = None) -> pa.Table:
    parts = sorted(folder.glob("part-*.parquet")) if folder.is_dir() else []
    if not parts:
        return schema.empty_table() if columns is None else schema.empty_table().select(columns)
    return ds.dataset([str(p) for p in parts], schema=schema, format="parquet").to_table(columns=columns)


def read_files(out: str | os.PathLike[str], columns: list[str] | None = None) -> pa.Table:
    """The ``files`` dataset of RESULTS ``out`` as one table (empty if none yet)."""
    return _dataset_table(Path(out) / "files", FILES_SCHEMA, columns)


def read_faces(out: str | os.PathLike[str], columns: list[str] | None = None) -> pa.Table:
    """The ``faces`` dataset of RESULTS ``out`` as one table (empty if none yet)."""
    return _dataset_table(Path(out) / "faces", FACES_SCHEMA, columns)


class ResultStore:
    """Append-only writer of RESULTS; see the module docstring.

    Parameters
    ----------
    out : path
        RESULTS folder (created, with ``files/`` and ``faces/``).
    resume : bool
        Keep earlier results (their hashes are in :attr:`done`). Without it, RESULTS must hold no
        results yet.
    flush_seconds, flush_rows : float, int
        A part file is written at least this often / for this many buffered files.
    """

    def __init__(self, out: str | os.PathLike[str], resume: bool = False, *, flush_seconds: float = 2.0,
                 flush_rows: int = 500) -> None:
        self.out = Path(out)
        self.files_dir, self.faces_dir = self.out / "files", self.out / "faces"
        self.run_id = time.strftime("%Y%m%dT%H%M%S") + "-" + uuid.uuid4().hex[:6]
        self.flush_seconds, self.flush_rows = flush_seconds, flush_rows
        self._files: list[dict[str, Any]] = []
        self._faces: list[dict[str, Any]] = []
        self._seq = 0
        self._last = time.monotonic()
        self._prepare(resume)
        self.done: dict[str, str] = self._done_hashes() if resume else {}

    # ------------------------------------------------------------------------------ set-up
    def _prepare(self, resume: bool) -> None:
        try:
            if self.out.exists() and not self.out.is_dir():
                raise StoreError(f"--out {self.out}: exists and is not a folder")
            self.files_dir.mkdir(parents=True, exist_ok=True)
            self.faces_dir.mkdir(parents=True, exist_ok=True)
            fd, probe = tempfile.mkstemp(prefix=".probe-", dir=self.files_dir)
            os.close(fd)
            os.unlink(probe)
        except StoreError:
            raise
        except OSError as err:
            raise StoreError(f"--out {self.out}: cannot write there: {err.strerror or err}") from err
        has_parts = any(self.files_dir.glob("part-*.parquet"))
        if has_parts and not resume:
            raise StoreError(f"--out {self.out}: already holds audit results; add --resume to finish them, "
                             "or choose another folder")
        for folder in (self.files_dir, self.faces_dir):
            _files.clean_stale_temps(folder)  # a part that a killed run did not finish writing
            for tmp in folder.glob(".part-*.tmp"):  # the same, left by a version before the shared helper
                with contextlib.suppress(OSError):
                    tmp.unlink()
        for part in self.faces_dir.glob("part-*.parquet"):
            if not (self.files_dir / part.name).exists():
                with contextlib.suppress(OSError):
                    part.unlink()  # faces of a batch whose files rows never landed: redone now

    def _done_hashes(self) -> dict[str, str]:
        t = read_files(self.out, ["sha256", "status"])
        return {h: s for h, s in zip(t.column("sha256").to_pylist(), t.column("status").to_pylist()) if h}

    # ------------------------------------------------------------------------------ writing
    def add(self, file_row: dict[str, Any], face_rows: Sequence[dict[str, Any]] = ()) -> None:
        """Buffer one file's rows; writes a part when the buffer is due."""
        self._files.append(file_row)
        self._faces.extend(f if "sha256" in f else {**f, "sha256": file_row.get("sha256")} for f in face_rows)
        if file_row.get("sha256"):
            self.done[file_row["sha256"]] = file_row["status"]
        self.maybe_flush()

    def maybe_flush(self) -> None:
        if self._files and (len(self._files) >= self.flush_rows or time.monotonic() - self._last >= self.flush_seconds):
            self.flush()

    def flush(self) -> None:
        """Write the buffered rows as one faces part and one files part (in that order)."""
        self._last = time.monotonic()
        if not self._files:
            return
        name = f"part-{self.run_id}-{self._seq:06d}.parquet"
        self._write(self.faces_dir / name, _table(self._faces, FACES_SCHEMA))
        self._write(self.files_dir / name, _table(self._files, FILES_SCHEMA))
        self._seq += 1
        self._files, self._faces = [], []

    @staticmethod
    def _write(target: Path, table: pa.Table) -> None:
        """One part file, atomically (:func:`occsurf.bridge.exchange.files.atomic_write`)."""
        try:
            _files.atomic_write(target, lambda fh: pq.write_table(table, fh, compression="zstd"))
        except OSError as err:  # ExchangeError (an OSError) names the path and the reason
            raise StoreError(str(err) if isinstance(err, ExchangeError) else
                             f"{target}: cannot write: {err.strerror or err}") from err
