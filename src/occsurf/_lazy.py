"""Lazy package attributes (PEP 562), shared by ``occsurf``, ``occsurf.bridge`` and its rooms.

A package lists its public names and the module each lives in; :func:`lazy_exports` gives the
module-level ``__getattr__`` and ``__dir__`` that import the module on the first access to a name
and keep the value in the package's namespace (later accesses are plain attribute reads).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_exports(package: str, exports: dict[str, str], namespace: dict[str, Any]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package`` whose ``exports`` map each name to its module
    (absolute, or relative to ``package`` with a leading dot); ``namespace`` is the package's
    ``globals()``."""

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(list(namespace) + sorted(exports))

    return __getattr__, __dir__
