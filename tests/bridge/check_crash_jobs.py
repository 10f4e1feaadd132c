"""Jobs for ``test_cli_check.py`` in place of ``occsurf check``'s worker job
(:func:`occsurf.bridge.quality.check_files.check_job`): the same job, but the worker dies (SIGSEGV, as a
fault inside OCC would end it) on one face or one picture, named by an environment variable, every time
it gets there."""

from __future__ import annotations

import os
import signal
from typing import Any


def _segfault() -> None:
    os.kill(os.getpid(), signal.SIGSEGV)


def crash_on_face(item: dict[str, Any]) -> Any:
    """Dies while checking face ``$OCCSURF_TEST_CRASH_FACES`` (comma-separated indices)."""
    from occsurf.bridge.quality import report
    from occsurf.bridge.quality.check_files import check_job

    targets = {int(k) for k in os.environ["OCCSURF_TEST_CRASH_FACES"].split(",")}
    original = report._check_face

    def crashing(face: Any, *args: Any, **kwargs: Any) -> Any:
        if face.index in targets:
            _segfault()
        return original(face, *args, **kwargs)

    report._check_face = crashing
    return check_job(item)


def crash_on_picture(item: dict[str, Any]) -> Any:
    """Dies while drawing the picture file ``$OCCSURF_TEST_CRASH_PICTURE``."""
    from occsurf.bridge.quality import pictures
    from occsurf.bridge.quality.check_files import check_job

    target = os.environ["OCCSURF_TEST_CRASH_PICTURE"]
    original = pictures.PngWriter.write

    def crashing(self: Any, path: Any, rgb: Any) -> Any:  # the picture rendered, handed to the writer
        if os.path.basename(str(path)) == target:
            _segfault()
        return original(self, path, rgb)

    pictures.PngWriter.write = crashing  # type: ignore[method-assign]
    return check_job(item)
