"""Every docstring example (``>>>``) in the package runs and prints what it says (doctest).

The walker imports every module of ``rigid_rot_sim`` (pkgutil.walk_packages; ROS is installed by
``make setup``, so nothing is skipped) and runs the examples of each as one test. A new example in any
module is picked up without editing this file. Output is compared with NORMALIZE_WHITESPACE and
ELLIPSIS, as numpy's and scipy's doctests are.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import numpy as np
import pytest

import rigid_rot_sim

FLAGS = doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS


def module_names() -> list[str]:
    return sorted(
        info.name for info in pkgutil.walk_packages(rigid_rot_sim.__path__, prefix=f"{rigid_rot_sim.__name__}.")
    ) + [rigid_rot_sim.__name__]


def examples(name: str) -> list[doctest.DocTest]:
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    return [test for test in finder.find(module, name, extraglobs={"np": np}) if test.examples]


MODULES = module_names()
WITH_EXAMPLES = [name for name in MODULES if examples(name)]


def test_the_walker_finds_the_package_and_its_examples():
    """Guards the walk itself: the modules the review named have examples, and they are found."""
    assert "rigid_rot_sim.core.exact" in WITH_EXAMPLES
    assert "rigid_rot_sim.core.inertia" in WITH_EXAMPLES
    assert len(MODULES) > 50


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_docstring_examples_run(name):
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for test in examples(name):
        runner.run(test)
    results = runner.summarize(verbose=False)
    assert results.failed == 0, f"{name}: {results.failed} of {results.attempted} examples failed (output above)"
