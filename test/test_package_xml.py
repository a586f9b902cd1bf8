"""The package manifests as rosdep and colcon read them: every dependency key resolves.

``rosdep install --from-paths ... --ignore-src`` stops at the first key it cannot resolve, so
each key of both package.xml files must be in ``test/data/rosdep_keys.yaml`` (resolvable keys,
with where rosdistro defines them), or be skipped by the rosdep recipe of docs/install.md, which then
pip-installs it. The skip list must name exactly the unresolvable keys: no more, no fewer.
"""

import re
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
MANIFESTS = [ROOT / "package.xml", ROOT / "rigid_rot_msgs" / "package.xml"]
KEYS = yaml.safe_load((ROOT / "test" / "data" / "rosdep_keys.yaml").read_text())
DEPEND_TAGS = (
    "depend",
    "build_depend",
    "buildtool_depend",
    "build_export_depend",
    "buildtool_export_depend",
    "exec_depend",
    "test_depend",
    "doc_depend",
)
#: Packages of this repository: rosdep resolves them from the source paths (--ignore-src).
OWN = {"rigid_rot_sim", "rigid_rot_msgs"}


def declared_keys(manifest: Path) -> set[str]:
    root = ElementTree.parse(manifest).getroot()
    return {element.text.strip() for tag in DEPEND_TAGS for element in root.findall(tag)}


#: Where the colcon workspace recipe (rosdep install, colcon build) is documented.
RECIPE = ROOT / "docs" / "install.md"


def readme_rosdep_commands() -> list[str]:
    text = RECIPE.read_text()
    return [line.strip() for line in text.splitlines() if line.strip().startswith("rosdep install")]


def skipped_keys(command: str) -> set[str]:
    match = re.search(r"--skip-keys[ =](\"[^\"]*\"|'[^']*'|\S+)", command)
    return set(match.group(1).strip("\"'").split()) if match else set()


def test_every_key_resolves_or_is_skipped_exactly_by_the_readme_recipe():
    resolvable = set(KEYS["system"]) | set(KEYS["ros"]) | OWN
    keys = set().union(*(declared_keys(m) for m in MANIFESTS))
    assert keys, "no dependency keys found"
    assert not keys & set(KEYS["not_keys"]), (
        f"keys that rosdistro does not define: {sorted(keys & set(KEYS['not_keys']))}"
    )
    unresolvable = keys - resolvable
    (command,) = readme_rosdep_commands()
    assert skipped_keys(command) == unresolvable, (
        f"{RECIPE.relative_to(ROOT)}: `{command}` must skip exactly {sorted(unresolvable)}"
    )
    # both packages are found by rosdep (rigid_rot_msgs sits inside the ament_python package)
    assert "--from-paths src src/rigid_rot_sim/rigid_rot_msgs" in command and "--ignore-src" in command


def test_the_key_list_says_where_each_key_comes_from():
    assert KEYS["source"].startswith("ros/rosdistro@")
    assert all("python.yaml" in where for where in KEYS["system"].values())
    assert not set(KEYS["system"]) & set(KEYS["not_keys"])


def test_manifests_are_valid_format_3_for_catkin_pkg():
    from catkin_pkg.package import parse_package

    for manifest in MANIFESTS:
        package = parse_package(str(manifest))  # raises InvalidPackage on a schema violation
        package.validate()
        assert package.package_format == 3
    runtime = {d.name for d in parse_package(str(ROOT / "package.xml")).exec_depends}
    # what the live /tf, the scene lookup and the launch file need where ROS is installed
    assert {"tf2_msgs", "ament_index_python", "launch", "launch_ros"} <= runtime
