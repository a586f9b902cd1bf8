"""The fuzz tests reuse the node harness of test/ros/test_node.py (in-process node and client)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # generators.py
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ros"))  # test_node.py, test_node_hardening.py

from test_node import context, harness  # noqa: F401  (fixtures)
