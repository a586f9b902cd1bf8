"""How the core compiles its kernels: numba ``njit`` with an on-disk cache, no fastmath.

:func:`compiled` is ``numba.njit(cache=True, **options)``: fastmath stays off so that a
kernel gives the same bits run to run and process to process (the node and
``rigid-rot resim`` run the same compiled code). ``make setup`` compiles every kernel once
(:mod:`rigid_rot_sim.core.precompile`), so neither the node nor the CLI pays JIT time.

Where the cache lives: ``__pycache__`` next to the sources (numba's in-tree cache), or
under ``NUMBA_CACHE_DIR`` when that is set. numba invalidates a cached kernel only when
the file of its entry point changes, but the kernels are built from helpers in several
modules (``register_jitable``); so the cache of every compiled function of this package
is keyed on the contents of all its core sources instead: editing any of them, or
checking out another commit, recompiles on next use instead of running stale code.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, overload

from numba import njit
from numba.core import caching, config

_CORE = Path(__file__).resolve().parent


@functools.cache
def sources_fingerprint() -> str:
    """SHA-256 of every Python source of ``rigid_rot_sim/core`` (names and contents)."""
    digest = hashlib.sha256()
    for path in sorted(_CORE.rglob("*.py")):
        digest.update(str(path.relative_to(_CORE)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _ours(py_file: str) -> bool:
    try:
        return Path(py_file).resolve().is_relative_to(_CORE)
    except OSError:
        return False


class _CoreInTreeLocator(caching.InTreeCacheLocator):
    """numba's in-tree cache, stamped with :func:`sources_fingerprint`."""

    def get_source_stamp(self) -> Any:
        return sources_fingerprint()

    @classmethod
    def from_function(cls, py_func: Callable[..., Any], py_file: str) -> Any:
        numba_config: Any = config  # numba's config fills its names at import: no types to read
        if numba_config.CACHE_DIR or not _ours(py_file):
            return None
        parent: Any = super().from_function  # numba's caching API is untyped
        return parent(py_func, py_file)


class _CoreUserDirLocator(caching.UserProvidedCacheLocator):
    """The ``NUMBA_CACHE_DIR`` cache, stamped with :func:`sources_fingerprint`."""

    def get_source_stamp(self) -> Any:
        return sources_fingerprint()

    @classmethod
    def from_function(cls, py_func: Callable[..., Any], py_file: str) -> Any:
        if not _ours(py_file):
            return None
        parent: Any = super().from_function  # numba's caching API is untyped
        return parent(py_func, py_file)


for _locator in (_CoreInTreeLocator, _CoreUserDirLocator):
    if _locator not in caching.CacheImpl._locator_classes:
        caching.CacheImpl._locator_classes.insert(0, _locator)


_F = TypeVar("_F", bound=Callable[..., Any])


@overload
def compiled(function: _F) -> _F: ...


@overload
def compiled(function: None = None, **options: Any) -> Callable[[_F], _F]: ...


def compiled(function: Callable[..., Any] | None = None, **options: Any) -> Any:
    """``numba.njit(cache=True, **options)`` (usable bare or with options); never fastmath."""
    if options.get("fastmath"):
        raise ValueError("core kernels are compiled without fastmath (bit-reproducible results)")
    decorator = njit(cache=True, **options)
    return decorator if function is None else decorator(function)
