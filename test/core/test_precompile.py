"""The kernels' stamp (core/precompile.py): a run on an install whose kernels were never compiled says so first.

Compiling every kernel takes minutes on a loaded machine, so ``exercise`` (run by ``make setup`` and by
every start of the node on this checkout, which load it from the cache) is replaced here by a recorder:
what is checked is the decision and the stamp, keyed on the core's sources.
"""

from __future__ import annotations

import os
from pathlib import Path

from rigid_rot_sim.core import precompile
from rigid_rot_sim.core.jit import sources_fingerprint


def test_the_stamp_is_named_by_the_sources_and_lives_in_the_cache_directory():
    path = precompile.stamp_path()
    assert path.name == f"rigid_rot_sim-kernels-{sources_fingerprint()[:16]}.stamp"
    cache = os.environ.get("NUMBA_CACHE_DIR")
    assert path.parent == (Path(cache) if cache else Path(precompile.__file__).parent / "__pycache__")


def test_ensure_compiled_says_it_compiles_once_then_finds_the_stamp(tmp_path, monkeypatch):
    stamp = tmp_path / "cache" / "rigid_rot_sim-kernels-test.stamp"
    monkeypatch.setattr(precompile, "stamp_path", lambda: stamp)
    compiled, said = [], []
    monkeypatch.setattr(precompile, "exercise", lambda: compiled.append(True))
    assert not precompile.kernels_cached()
    spent = precompile.ensure_compiled(said.append)
    assert compiled == [True] and spent >= 0.0 and stamp.is_file()
    assert len(said) == 1 and "compiling the numba kernels once for this install" in said[0]
    assert precompile.kernels_cached()
    assert precompile.ensure_compiled(said.append) == 0.0 and compiled == [True] and len(said) == 1


def test_a_read_only_cache_directory_compiles_every_time_without_failing(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    monkeypatch.setattr(precompile, "stamp_path", lambda: blocked / "rigid_rot_sim-kernels-test.stamp")
    monkeypatch.setattr(precompile, "exercise", lambda: None)
    said: list[str] = []
    precompile.ensure_compiled(said.append)
    precompile.ensure_compiled(said.append)
    assert len(said) == 2  # no stamp could be left: said (and compiled) again
