"""``occsurf audit``: quality and exchange audit of whole CAD corpora on Dask.

One task per STEP/IGES file, on a Dask ``LocalCluster`` (one process per core, one thread each)
or an existing cluster: a crash-isolated read (a persistent reader process per worker thread, so a
segmentation fault inside OCC costs that file and names its signal), the inspect numbers of every
face (:func:`occsurf.bridge.validation.inspect.inspect_model`), a STEP round trip, and the quality
summary hook. Results stream into Parquet datasets (``RESULTS/files``, ``RESULTS/faces``) as
tasks finish; ``--resume`` skips content already audited (SHA-256).

==================  ================================================================================
:mod:`.corpus`      PATH expansion (files, folders, globs, list files), STEP/IGES detection, SHA-256
:mod:`.tasks`       the per-file task (:func:`~.tasks.audit_task` on Dask, :func:`~.tasks.audit_job`
                    in the reader)
:mod:`.reader`      the persistent crash-isolated reader process of each worker thread
:mod:`.store`       the Parquet datasets: atomic part files, resume by content hash
:mod:`.summary`     ``summary.json`` and ``summary.html``
:mod:`.cluster`     the Dask client: ``LocalCluster`` or ``--scheduler ADDRESS``
:mod:`.run`         :func:`audit`, the driver
:mod:`.fill_file`   ``occsurf fill`` in crash-isolated workers, several holes at once
:mod:`.repair`      assess, match smooth edges, fair wiggles, assess again (``occsurf repair``); it sits
                    here because it drives both the quality and the modeling rooms
:mod:`.match_file`  ``occsurf match`` and ``occsurf repair`` in a worker process
:mod:`.fit_file`    ``occsurf fit`` in a worker process (progress through a file the command follows)
:mod:`.render_file` ``occsurf render`` in a worker process
==================  ================================================================================

Names are loaded on first use (``dask``, ``pyarrow`` and OCC are not imported by ``import
occsurf.bridge.audit``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__all__ = ["audit", "AuditResult", "AuditInputError", "CorpusError", "StoreError", "ClusterError", "read_files", "read_faces",
           "write_summary"]

if TYPE_CHECKING:  # the lazily served names, for type checkers and IDEs
    from .cluster import (
        ClusterError,
    )
    from .corpus import (
        CorpusError,
    )
    from .run import (
        AuditInputError,
        AuditResult,
        audit,
    )
    from .store import (
        StoreError,
        read_faces,
        read_files,
    )
    from .summary import (
        write_summary,
    )

_WHERE = {"audit": ".run", "AuditResult": ".run", "AuditInputError": ".run", "CorpusError": ".corpus", "StoreError": ".store",
          "ClusterError": ".cluster", "read_files": ".store", "read_faces": ".store", "write_summary": ".summary"}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
