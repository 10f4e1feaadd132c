"""Jobs for ``test_isolation.py``, run by :func:`occsurf.bridge.isolation.run_jobs` in a worker process
(a job must be a module-level function of a module the worker can import).

Set ``OCCSURF_TEST_IMPORT_DELAY`` (seconds) to make importing this module slow: the worker's start-up.
"""

from __future__ import annotations

import os
import signal
import time
from typing import Any

if os.environ.get("OCCSURF_TEST_IMPORT_DELAY"):
    time.sleep(float(os.environ["OCCSURF_TEST_IMPORT_DELAY"]))


def behave(item: dict[str, Any]) -> dict[str, Any]:
    """Append the item's name to ``item["log"]`` (if given), then do what ``item["do"]`` says:
    ``'segv'`` (a segmentation fault; ``'segv_once'``: unless ``item["skip"]`` names something), ``'sleep'`` (``item["seconds"]``, default an hour),
    ``'raise'``, ``'chatter'`` (write to stdout, Python and fd 1), ``'nan'``; else return."""
    if item.get("log"):
        with open(item["log"], "a", encoding="utf-8") as fh:
            fh.write(item["name"] + "\n")
    action = item.get("do")
    if action == "segv" or (action == "segv_once" and not item.get("skip")):  # once: until a piece is skipped
        os.kill(os.getpid(), signal.SIGSEGV)
    elif action == "sleep":
        time.sleep(float(item.get("seconds", 3600)))
    elif action == "raise":
        raise RuntimeError("boom\nsecond line")
    elif action == "chatter":
        print("python chatter")
        os.write(1, b"native chatter\n")
    elif action == "nan":
        return {"name": item["name"], "value": float("nan")}
    elif action == "unserialisable":
        return {"name": item["name"], "value": object()}
    import occsurf

    return {"name": item["name"], "pid": os.getpid(), "occsurf": occsurf.__file__}
