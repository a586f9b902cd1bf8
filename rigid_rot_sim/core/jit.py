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

:func:`serial_and_parallel` compiles one loop body twice, serially and over the cores (numba runs
``prange`` as ``range`` without ``parallel=True``), so the two never drift apart.
"""

from __future__ import annotations

import functools
import hashlib
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast, overload

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


def serial_and_parallel(function: _F, **options: Any) -> tuple[_F, _F]:
    """One kernel body compiled twice: ``(serial, parallel)``, the second with ``parallel=True``.

    ``function`` loops with ``numba.prange``: the serial twin runs it as ``range`` (no start-up of the
    parallel region, for small jobs), the parallel one over the cores. numba's cache files are named
    after the function's qualified name and do not tell the two compilations apart, so the parallel
    twin compiles a copy of the function named ``<name>_parallel``.
    """
    if not isinstance(function, types.FunctionType):
        raise TypeError(f"serial_and_parallel compiles a plain function, got {function!r}")
    name = f"{function.__name__}_parallel"
    twin = types.FunctionType(
        function.__code__, function.__globals__, name, function.__defaults__, function.__closure__
    )
    twin.__qualname__ = f"{function.__qualname__}_parallel"
    twin.__module__ = function.__module__
    twin.__doc__ = function.__doc__
    serial: _F = compiled(**options)(function)
    parallel: _F = compiled(parallel=True, **options)(cast(_F, twin))
    return serial, parallel
