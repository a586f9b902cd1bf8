"""The documentation says what the code does: its references import, its examples are accepted.

* Every dotted name ``rigid_rot_sim.x.y`` and every Sphinx role (``:mod:``, ``:class:``, ``:func:``,
  ``:meth:``, ``:attr:``, ``:data:``, ``:exc:``) in the README, in every ``docs/*.md`` (new pages are
  picked up by the glob) and in the torque-route docstring of ``rigid_rot_sim/ros/__init__.py``
  resolves by import. The route's double-backquoted steps (``inputs.TorqueInputs.torque_callback``,
  ``Simulator.submit_torque``) resolve too: relative to ``rigid_rot_sim`` or ``rigid_rot_sim.ros``, or
  through a class of the package named by its first part.
* The shell examples in code blocks (indented by 4 or fenced) are ones the code accepts: every
  ``rigid-rot ...`` line parses with the command's own argparse, names a scene that exists and a frame
  the default scene frames have; every ``ros2 topic pub`` line publishes to a torque topic of a shipped
  scene (as the default node expands it), with its message type, and a message that the engine admits
  (``Simulator.receive_torque``: frame, force, values), as the node would.

A failure names the file and the reference or the line, and says what to correct.
"""

from __future__ import annotations

import ast
import importlib
import re
import shlex
from collections.abc import Iterator
from functools import cache
from pathlib import Path
from typing import Any

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "rigid_rot_sim"
ROUTE_MODULE = PACKAGE / "ros" / "__init__.py"


def documents() -> list[Path]:
    """The README and every page under docs/ (recursively, so new pages are checked too)."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def route_docstring() -> str:
    return ast.get_docstring(ast.parse(ROUTE_MODULE.read_text(encoding="utf-8"))) or ""


def test_there_are_documents_and_a_route():
    assert (ROOT / "docs").is_dir() and len(documents()) > 1
    assert "route" in route_docstring()


# --- references ---------------------------------------------------------------------------------

#: A dotted name that starts with the package; not a path (``launch/rigid_rot_sim.launch.py``) and not a
#: file name (the last part is checked against FILE_SUFFIXES).
DOTTED = re.compile(r"(?<![\w/.-])rigid_rot_sim(?:\.[A-Za-z_]\w*)+")
FILE_SUFFIXES = {"py", "yaml", "yml", "json", "md", "mcap", "xml", "launch", "rst", "txt", "cfg", "toml"}
#: :role:`target`, :role:`~target`, :role:`text <target>`.
ROLE = re.compile(r":(?:py:)?(?:mod|class|func|meth|attr|data|exc|obj):`(?:[^`<]*<)?~?([\w.]+)>?`")
#: ``a.b.c`` or ``a.b.c(args)``: a double-backquoted dotted name, call arguments dropped.
LITERAL = re.compile(r"``([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)(?:\([^`]*\))?``")


def resolve(dotted: str) -> Any:
    """The object ``dotted`` names: the longest importable module prefix, then attributes."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError as error:
            if error.name is not None and not dotted.startswith(error.name):
                raise  # a real missing dependency inside the module, not a wrong name
            continue
        for attribute in parts[cut:]:
            obj = getattr(obj, attribute)
        return obj
    raise ModuleNotFoundError(dotted)


def resolves(dotted: str) -> bool:
    try:
        resolve(dotted)
    except (ImportError, AttributeError):
        return False
    return True


@cache
def package_classes() -> dict[str, list[str]]:
    """Class name -> the modules of the package that define a class of that name (read with ast)."""
    classes: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef):
                classes.setdefault(node.name, []).append(module)
    return classes


def references(text: str) -> set[str]:
    """The package-qualified names and role targets in ``text`` (relative role targets kept with their dot)."""
    found = {match.rstrip(".") for match in DOTTED.findall(text)}
    found = {name for name in found if name.rsplit(".", 1)[-1] not in FILE_SUFFIXES}
    return found | set(ROLE.findall(text))


def document_references() -> Iterator[tuple[str, str]]:
    for path in documents():
        for name in sorted(references(path.read_text(encoding="utf-8"))):
            yield str(path.relative_to(ROOT)), name


@pytest.mark.parametrize(("document", "name"), list(document_references()))
def test_document_reference_resolves(document, name):
    candidates = [f"rigid_rot_sim{name}"] if name.startswith(".") else [name, f"rigid_rot_sim.{name}"]
    assert any(resolves(c) for c in candidates), (
        f"{document}: {name!r} does not resolve by import (tried {candidates}); "
        "the code moved or was renamed: correct the reference"
    )


def route_candidates(name: str) -> list[str]:
    """Where a name in the route docstring may live: a role target relative to rigid_rot_sim.ros, a name
    relative to the package or to rigid_rot_sim.ros, or a method of a package class named by its first part."""
    if name.startswith("."):
        return [f"rigid_rot_sim.ros{name}"]
    first = name.split(".")[0]
    rest = name.split(".", 1)[1:] if "." in name else []
    candidates = [name, f"rigid_rot_sim.{name}", f"rigid_rot_sim.ros.{name}"]
    candidates += [".".join([module, first, *rest]) for module in package_classes().get(first, [])]
    return candidates


def is_code_reference(name: str) -> bool:
    """Whether a double-backquoted name in the route is code: its first part is a room or module of the
    package (or of rigid_rot_sim.ros) or a class of the package. Others are parameters or keys
    (``commands.max_torque``)."""
    first = name.split(".")[0]
    return (
        first == "rigid_rot_sim"
        or first in package_classes()
        or (PACKAGE / first).is_dir()
        or (PACKAGE / f"{first}.py").is_file()
        or (PACKAGE / "ros" / f"{first}.py").is_file()
    )


def route_references() -> list[str]:
    text = route_docstring()
    names = references(text) | {name for name in LITERAL.findall(text) if is_code_reference(name)}
    return sorted(names)


def test_route_names_steps():
    """The route is checked only if it keeps naming its steps in ``...``: guard against a reformat that
    drops them all (then the test below would pass on nothing)."""
    assert len(route_references()) >= 15, route_references()


@pytest.mark.parametrize("name", route_references())
def test_route_reference_resolves(name):
    candidates = route_candidates(name)
    assert any(resolves(c) for c in candidates), (
        f"rigid_rot_sim/ros/__init__.py route docstring: {name!r} resolves nowhere (tried {candidates}); "
        "the route must name the code it passes through: correct the step"
    )


# --- links -------------------------------------------------------------------------------------

LINK = re.compile(r"\]\(([^)\s]+)\)")


def document_links() -> Iterator[tuple[str, str]]:
    for path in documents():
        for target in LINK.findall(path.read_text(encoding="utf-8")):
            if "://" not in target and not target.startswith(("#", "mailto:")):
                yield str(path.relative_to(ROOT)), target


@pytest.mark.parametrize(("document", "target"), list(document_links()))
def test_relative_link_points_to_a_file(document, target):
    path = (ROOT / document).parent / target.split("#", 1)[0]
    assert path.exists(), f"{document}: link to {target!r}: {path.relative_to(ROOT)} does not exist"


# --- shell examples -----------------------------------------------------------------------------


def code_lines(text: str) -> Iterator[str]:
    """Commands in code blocks (4-space indented or fenced), continuation lines joined, comments dropped."""
    block: list[str] = []
    fenced = False
    for line in text.splitlines():
        if line.startswith("```"):
            fenced = not fenced
            continue
        if fenced or line.startswith("    "):
            block.append(line.strip())
    joined = "\n".join(block).replace("\\\n", " ")
    for line in joined.splitlines():
        try:
            words = shlex.split(line, comments=True)
        except ValueError:
            continue  # not a shell line (YAML, JSON, Python in a fenced block)
        if words:
            yield " ".join(shlex.quote(w) for w in words)


def shell_examples(program: str) -> list[tuple[str, list[str]]]:
    """(document, argv after the program) of each code line that runs ``program`` (any path to it)."""
    found = []
    for path in documents():
        for line in code_lines(path.read_text(encoding="utf-8")):
            words = shlex.split(line)
            for i, word in enumerate(words):
                if word == program or word.endswith("/" + program):
                    found.append((str(path.relative_to(ROOT)), words[i + 1 :]))
                    break
    return found


def without_ros_args(argv: list[str]) -> list[str]:
    return argv[: argv.index("--ros-args")] if "--ros-args" in argv else argv


def default_frames() -> set[str]:
    from rigid_rot_sim.scene.scene import Frames

    return {Frames().world, Frames().body}


def test_readme_has_shell_examples():
    assert shell_examples("rigid-rot"), "no rigid-rot example found: the parser of code blocks is broken"
    assert shell_examples("ros2"), "no ros2 example found: the parser of code blocks is broken"


@pytest.mark.parametrize(("document", "argv"), shell_examples("rigid-rot"))
def test_rigid_rot_example_is_accepted(document, argv, monkeypatch):
    from rigid_rot_sim.cli import build_parser
    from rigid_rot_sim.share import resolve_scene

    argv = without_ros_args(argv)
    if argv and argv[-1] in {"-h", "--help"}:
        return
    parser = build_parser()
    parser.exit_on_error = False
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # argparse exits for what exit_on_error does not cover
        raise AssertionError(f"{document}: `rigid-rot {shlex.join(argv)}` is refused by argparse ({exit_})") from None
    scene = getattr(args, "scene", None)
    if isinstance(scene, str) and argv[0] == "run":
        monkeypatch.chdir(ROOT)  # examples name paths relative to the checkout
        try:
            resolve_scene(scene)
        except ValueError as error:
            raise AssertionError(f"{document}: `rigid-rot {shlex.join(argv)}`: {error}") from None
    frame = getattr(args, "frame", None)
    if isinstance(frame, str) and argv[0] == "torque":
        assert frame in default_frames(), (
            f"{document}: `rigid-rot {shlex.join(argv)}`: frame {frame!r} is none of the default frames "
            f"{sorted(default_frames())}"
        )


@cache
def shipped_torque_topics() -> dict[str, list[tuple[str, Any]]]:
    """Expanded topic (default node name) -> [(scene name, its TopicInput)] over the shipped scenes."""
    from rclpy.expand_topic_name import expand_topic_name

    from rigid_rot_sim.ros.node import NODE_NAME
    from rigid_rot_sim.scene.scene import load_scene

    topics: dict[str, list[tuple[str, Any]]] = {}
    for path in sorted((ROOT / "config" / "scenes").glob("*.yaml")):
        scene = load_scene(path)
        for spec in scene.topic_inputs:
            topics.setdefault(expand_topic_name(spec.topic, NODE_NAME, "/"), []).append((path.stem, spec))
    return topics


def topic_pub_examples() -> list[tuple[str, list[str]]]:
    return [(doc, argv) for doc, argv in shell_examples("ros2") if argv[:2] == ["topic", "pub"]]


def test_there_is_a_topic_pub_example():
    assert topic_pub_examples(), "no `ros2 topic pub` example found in the documents"


@pytest.mark.parametrize(("document", "argv"), topic_pub_examples())
def test_ros2_topic_pub_example_is_accepted(document, argv):
    from rigid_rot_sim.run.commands import CommandRejected
    from rigid_rot_sim.run.simulator import Simulator
    from rigid_rot_sim.scene.scene import load_scene

    positional = [word for word in argv[2:] if not word.startswith("-")]
    assert len(positional) >= 3, f"{document}: `ros2 {shlex.join(argv)}`: expected TOPIC TYPE VALUES"
    topic, message_type, values = positional[:3]
    inputs = shipped_torque_topics().get(topic)
    assert inputs, (
        f"{document}: `ros2 {shlex.join(argv)}`: {topic!r} is no torque topic of a shipped scene under the "
        f"default node name (those are {sorted(shipped_torque_topics())})"
    )
    message = yaml.safe_load(values)
    frame_id = message.get("header", {}).get("frame_id", "")
    wrench = message.get("wrench", message)
    torque = [float(wrench.get("torque", wrench.get("vector", {})).get(axis, 0.0)) for axis in "xyz"]
    force = [float(wrench.get("force", {}).get(axis, 0.0)) for axis in "xyz"] if "wrench" in message else None
    for scene_name, spec in inputs:
        assert message_type.split("/")[-1] == spec.message_type, (
            f"{document}: {topic} takes {spec.message_type} in {scene_name}, the example sends {message_type}"
        )
        scene = load_scene(ROOT / "config" / "scenes" / f"{scene_name}.yaml")
        try:
            Simulator(scene).receive_torque(spec.topic, torque, frame_id, None, force)
        except CommandRejected as rejected:
            example = f"ros2 {shlex.join(argv)}"
            raise AssertionError(f"{document}: `{example}` is rejected by {scene_name}: {rejected}") from None
