"""The vendored interface packages equal upstream: simulation_interfaces 1.5.1 and tf2_msgs (Jazzy).

``make setup`` builds ``rigid_rot_msgs/vendor/*`` into the venv where the real packages are not installed.
Peers match by type name and, with rmw_zenoh and in recordings, by RIHS01 type hash, so the vendored
types must keep upstream's hashes. The hashes are read from the built (or installed) package's type
descriptions, the ``share/<package>/{msg,srv}/*.json`` that rosidl_generator_type_description writes and
rclpy and rosbag2 use.

Pinned values: upstream simulation_interfaces tag 1.5.1 (``a3c60ff``) through Jazzy's rosidl 4.6.6
(../shared/ros-review-2.md, section 4: the 3 messages and 5 services, checked against a full CMake build of
upstream and the JSON of the venv; also equal for 1.0.0, 1.2.0 and 1.5.0). A service's hash covers the
type descriptions of its ``_Request``, ``_Response`` and ``_Event`` (they are referenced types of it); the
review found those 15 equal to upstream as well, and they are pinned as the same build gives them.
A failure here means a vendored ``.msg``/``.srv`` no longer equals upstream: revert the change.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from ament_index_python.packages import get_package_share_directory

from rigid_rot_sim.share import ensure_ament_prefix_path

ROOT = Path(__file__).resolve().parents[1]
VENDOR = ROOT / "rigid_rot_msgs" / "vendor"

#: simulation_interfaces 1.5.1: the messages and services (ros-review-2.md, section 4).
UPSTREAM_1_5_1 = {
    "msg/Result": "RIHS01_cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17",
    "msg/SimulationState": "RIHS01_bb9f87ccdd98fba113052a512d9801e84ce732d0a2b3c2b0cb281828de36e415",
    "msg/SimulatorFeatures": "RIHS01_8b101c8529bc0ea3dcf056078254768f39832b9ef0adaf93bd5cea96c0de3305",
    "srv/GetSimulationState": "RIHS01_3362dcebee4b1afebbf9c4beee5c79c1455385aded62092a892d61fde8644f30",
    "srv/GetSimulatorFeatures": "RIHS01_abb9439c8cf196722a469fb6c68b44b484f198c2a1356ac38849a29c2a20a794",
    "srv/ResetSimulation": "RIHS01_4ce285d7ff9b8ac70dcc95161f32bf54c05a6f4b13427990e41ab40c36c39646",
    "srv/SetSimulationState": "RIHS01_a868b916dce49974f637ba252141258c4b07b0c06858b88af560e3eb6bfbcb30",
    "srv/StepSimulation": "RIHS01_913fe0653690ce6bf8f09f316e6a626747012e9fca31e26719910d417aa8565c",
}
#: Their request, response and event types (referenced by the services' descriptions above).
UPSTREAM_1_5_1_PARTS = {
    "srv/GetSimulationState_Event": "RIHS01_34cdb4f06989af235d3403650bae196550a928870b69740899fadc922899748f",
    "srv/GetSimulationState_Request": "RIHS01_c6d65bc5c0a95ca2886bc57f146f803e01722c84ddb5acd5f32a4417f55eecfb",
    "srv/GetSimulationState_Response": "RIHS01_dc80ce852a5ab04c2b23cdd47910cee1bcc46e0f1931cac85825e6916b15517f",
    "srv/GetSimulatorFeatures_Event": "RIHS01_2716384dc5445ebe9e7eda1021e5739b8c62ab985dccc3c506ba840c67e810b8",
    "srv/GetSimulatorFeatures_Request": "RIHS01_982b8c1adef1d556f6ecdc019d1269fc39413626a9222d73b4fc874bd798b7db",
    "srv/GetSimulatorFeatures_Response": "RIHS01_ede4dc8227cbb2f86a24612c999dcaa67d17dab21dab566cefdc233e7a2a65d1",
    "srv/ResetSimulation_Event": "RIHS01_dd7cbcb886e466ab23216c7033f25e8534e5255a73877944338bb301e7b29626",
    "srv/ResetSimulation_Request": "RIHS01_2c766d09c3aa30f01fadc55a42fd760b63db358c7d1d3b6a64ea9978225ffbc7",
    "srv/ResetSimulation_Response": "RIHS01_718428121e0f1755720878d3c28f1688da7581ee5a5d56d26d10d941a28a50a0",
    "srv/SetSimulationState_Event": "RIHS01_aea08cbc96bd8c6c88ba9ab79f98a73bf3028c35ea8e1f47bf5fc9d82cbc6b9a",
    "srv/SetSimulationState_Request": "RIHS01_73283477d36ba619db2ac37a3e599077ca244502c9d8ca2a7183afcb2224f476",
    "srv/SetSimulationState_Response": "RIHS01_6351aebf2bbf06e2993977918b944240f7403b532a9e4a344c53e71a56afd174",
    "srv/StepSimulation_Event": "RIHS01_1796fda54ba381a56d32c10784cabf78e14d6c8a1912a515a47d6597ad431d90",
    "srv/StepSimulation_Request": "RIHS01_cda33f6887815f3dce0f90e61fd8efd39bda13ae264ddede15c33fbad890630e",
    "srv/StepSimulation_Response": "RIHS01_5b4acf2d0ce7c3fc125d0bef2acb9b5a81377e80db6b696b81beeffb9824fb5c",
}
#: The action SimulateSteps and its parts (vendored verbatim from tag 1.5.1): not in the review's list;
#: computed from the upstream ``action/SimulateSteps.action`` (with its ``msg/Result.msg``) by Jazzy's
#: rosidl type-description generator in a scratch CMake package outside this repository's build.
UPSTREAM_1_5_1_ACTION = {
    "action/SimulateSteps": "RIHS01_f0837c898e1219cd73bf4c041feab41e8c533e8e1057e982744dba7b093467eb",
    "action/SimulateSteps_Goal": "RIHS01_3f02c5df1dcdc7c08efee7f47c953c42c11686e0df8f8bbfb2d7e901f0d440d2",
    "action/SimulateSteps_Result": "RIHS01_a1384eaee4ca7ae9238e612dfe26939dd0922cae664be1b5886cf773718823dc",
    "action/SimulateSteps_Feedback": "RIHS01_735661ca01115eb9bca068c3f2cb79bd790cd46962317ce7ee9081a5915c9a77",
    "action/SimulateSteps_FeedbackMessage": "RIHS01_a30dee7ee7380769e616406ec5067b238aa2b27e1dbd7a5957fba1d908d7754d",
    "action/SimulateSteps_SendGoal": "RIHS01_504407b9ff5617a737df8222cf581452b4f2e699e11e940d8d36590c5fb07d01",
    "action/SimulateSteps_SendGoal_Request": "RIHS01_275e6fd2fafc5d33dcdc83bdea6de5cf29f30b9df74a3b9514a8c5d501fd0fe3",
    "action/SimulateSteps_SendGoal_Response": "RIHS01_755f44a68d1e8d116f50dfed7ab30a140137fb71ad59eca4851d55abe2b3d4c2",
    "action/SimulateSteps_GetResult": "RIHS01_a1dae0516ab5c70d6d797e1bcd55c9448dfbb1966643f1ebd3e3f153d8169ae0",
    "action/SimulateSteps_GetResult_Request": "RIHS01_4591b0bfbcb881003bbd46a2acebcaddceb977e5352905218688ce5ed051fdeb",
    "action/SimulateSteps_GetResult_Response": (
        "RIHS01_5658172e771cb145a986a8ef4c2b80b5407b741038453b8539e35bed5ff23207"
    ),
}
#: The event types of the action's two services: built from the verbatim upstream file, not pinned.
ACTION_SERVICE_EVENTS = {"action/SimulateSteps_SendGoal_Event", "action/SimulateSteps_GetResult_Event"}
TF2_MSGS = {"msg/TFMessage": "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"}


def built_hashes(package: str) -> dict[str, str]:
    """Type name (``msg/X``, ``srv/Y_Request``) -> RIHS01 hash, over the package's installed descriptions."""
    ensure_ament_prefix_path()  # the venv's console scripts do this; a bare `python -m pytest` needs it too
    share = Path(get_package_share_directory(package))
    hashes: dict[str, str] = {}
    for path in sorted(share.glob("*/*.json")):
        for entry in json.loads(path.read_text(encoding="utf-8"))["type_hashes"]:
            owner, _, name = entry["type_name"].partition("/")
            if owner == package:
                hashes[name] = entry["hash_string"]
    return hashes


def test_simulation_interfaces_has_the_23_upstream_types_and_the_action():
    pinned = UPSTREAM_1_5_1 | UPSTREAM_1_5_1_PARTS
    assert len(pinned) == 23
    expected = set(pinned) | set(UPSTREAM_1_5_1_ACTION) | ACTION_SERVICE_EVENTS
    assert set(built_hashes("simulation_interfaces")) == expected


@pytest.mark.parametrize(
    ("type_name", "expected"), sorted((UPSTREAM_1_5_1 | UPSTREAM_1_5_1_PARTS | UPSTREAM_1_5_1_ACTION).items())
)
def test_simulation_interfaces_hash_is_upstream_1_5_1(type_name, expected):
    assert built_hashes("simulation_interfaces")[type_name] == expected, (
        f"simulation_interfaces/{type_name}: the built type's hash differs from upstream 1.5.1: "
        "the vendored definition must equal upstream"
    )


def test_tf2_msgs_hash_is_upstream():
    assert built_hashes("tf2_msgs") == TF2_MSGS


@pytest.mark.parametrize("package", ["simulation_interfaces", "tf2_msgs"])
def test_the_built_definitions_are_the_vendored_ones(package):
    """Where the venv built the package from vendor/, its installed definitions are the vendored files
    (so the hashes above are those of this repository's files, not of some other installation)."""
    ensure_ament_prefix_path()
    share = Path(get_package_share_directory(package))
    source = VENDOR / package
    patterns = ("msg/*.msg", "srv/*.srv", "action/*.action")
    vendored = sorted(p.relative_to(source) for pattern in patterns for p in source.glob(pattern))
    assert vendored
    if not str(share).startswith(str(ROOT)):
        return  # a real installation (apt) is used; the hashes above still had to match
    for relative in vendored:
        assert (share / relative).read_text(encoding="utf-8") == (VENDOR / package / relative).read_text(
            encoding="utf-8"
        ), f"{share / relative} is not the vendored file: rerun make setup"


def test_vendored_simulation_interfaces_is_labelled_1_5_1():
    manifest = ET.parse(VENDOR / "simulation_interfaces" / "package.xml").getroot()
    assert manifest.findtext("version") == "1.5.1"
    assert "1.5.1" in (VENDOR / "README.md").read_text(encoding="utf-8")


def test_the_action_type_imports_with_the_upstream_fields():
    from simulation_interfaces.action import SimulateSteps

    assert SimulateSteps.Goal().steps == 0 and SimulateSteps.Goal.get_fields_and_field_types() == {"steps": "uint64"}
    assert SimulateSteps.Feedback.get_fields_and_field_types() == {
        "completed_steps": "uint64",
        "remaining_steps": "uint64",
    }
    assert SimulateSteps.Result.get_fields_and_field_types() == {"result": "simulation_interfaces/Result"}
