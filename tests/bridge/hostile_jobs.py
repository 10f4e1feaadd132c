"""Jobs for ``test_hostile_input.py`` in place of the reader process's job (same item, a worse end)."""

from __future__ import annotations

import os
import signal
import time
from typing import Any


def crash(item: dict[str, Any]) -> None:
    """A segmentation fault while reading ``item["path"]``, as OCC's parser has shown."""
    os.kill(os.getpid(), signal.SIGSEGV)


def hang(item: dict[str, Any]) -> None:
    """A reader that never returns."""
    time.sleep(3600)
