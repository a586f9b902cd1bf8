"""launch/rigid_rot_sim.launch.py, without importing it: ``launch`` is not on PyPI.

The file is compiled (syntax) and read as a syntax tree: its launch arguments are the
documented ones, it starts this package's node executable, and nothing in the package or the
tests imports ``launch`` (the venv would fail at import).
"""

import ast
import py_compile
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LAUNCH_FILE = ROOT / "launch" / "rigid_rot_sim.launch.py"


def test_launch_file_compiles(tmp_path):
    py_compile.compile(str(LAUNCH_FILE), cfile=str(tmp_path / "launch.pyc"), doraise=True)


def test_launch_arguments_and_node_are_the_documented_ones():
    tree = ast.parse(LAUNCH_FILE.read_text())
    arguments = next(
        node.value
        for node in ast.walk(tree)
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "ARGUMENTS" for t in node.targets)
    )
    names = {key.value for key in arguments.keys}
    assert names == {"scene", "params_file", "namespace", "node_name", "remappings", "record_path"}
    docstring = ast.get_docstring(tree)
    assert all(re.search(rf"^{name}\s", docstring, re.M) for name in names), "every argument is documented"
    calls = [node for node in ast.walk(tree) if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "Node"]
    (node_call,) = calls
    keywords = {k.arg: k.value for k in node_call.keywords}
    assert keywords["package"].value == "rigid_rot_sim"
    assert keywords["executable"].value == "rigid_rot_sim_node"
    assert {"name", "namespace", "parameters", "remappings"} <= keywords.keys()


def test_nothing_imports_launch_and_setup_installs_the_file():
    pattern = re.compile(r"^\s*(from|import)\s+launch(_ros)?\b", re.M)
    sources = [*ROOT.joinpath("rigid_rot_sim").rglob("*.py"), *ROOT.joinpath("test").rglob("*.py")]
    assert not [str(p) for p in sources if pattern.search(p.read_text())]
    assert 'glob.glob("launch/*.launch.py")' in (ROOT / "setup.py").read_text()
