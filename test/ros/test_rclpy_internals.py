"""rclpy's internals are used in one module only: rigid_rot_sim/ros/rclpy_internals.py (issue 39).

Whatever the node loop needs beyond rclpy's public API (the C wait set, the take, a timer a Waitable
owns, rclpy's own /clock subscription) lives there, each use with the public API it stands in for; a
second module reaching into rclpy fails here.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "rigid_rot_sim"
HOME = "ros/rclpy_internals.py"
#: Attribute names that only rclpy's internals have (the C handles' methods, the C wait set).
INTERNAL_ATTRIBUTES = {"take_message", "call_timer", "is_timer_ready", "WaitSet"}
#: Names that mark a use: the C extension.
INTERNAL_NAMES = {"_rclpy", "rclpy_implementation"}


def internal_uses(source: str) -> list[str]:
    """What in ``source`` reaches into rclpy's internals: ``rclpy.impl`` imports, internal names and methods."""
    uses = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("rclpy.impl"):
            uses.append(f"line {node.lineno}: from {node.module} import ...")
        elif isinstance(node, ast.Import):
            uses += [f"line {node.lineno}: import {a.name}" for a in node.names if a.name.startswith("rclpy.impl")]
        elif isinstance(node, ast.Attribute) and node.attr in INTERNAL_ATTRIBUTES:
            uses.append(f"line {node.lineno}: .{node.attr}")
        elif isinstance(node, ast.Name) and node.id in INTERNAL_NAMES:
            uses.append(f"line {node.lineno}: {node.id}")
        elif isinstance(node, ast.FunctionDef) and node.name == "create_subscription":
            uses.append(f"line {node.lineno}: Node.create_subscription overridden")
    return uses


def test_rclpy_internals_are_used_in_one_module():
    users = {
        str(path.relative_to(PACKAGE)): uses
        for path in sorted(PACKAGE.rglob("*.py"))
        if (uses := internal_uses(path.read_text(encoding="utf-8")))
    }
    assert set(users) == {HOME}, {name: uses for name, uses in users.items() if name != HOME}


def test_the_check_finds_each_kind_of_use():
    planted = {
        "from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy": 1,
        "import rclpy.impl.rcutils_logger": 1,
        "got = subscription.handle.take_message(t, False)": 1,
        "timer.handle.call_timer()": 1,
        "class N:\n    def create_subscription(self, *a):\n        pass": 1,
        "subscription.take_message_public = 1\nnode.create_publisher()": 0,
    }
    for source, count in planted.items():
        assert len(internal_uses(source)) >= count and (count or not internal_uses(source)), source
