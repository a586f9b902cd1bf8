"""The standard interfaces the node serves have the upstream RIHS01 type hashes.

A Jazzy peer built against apt's ``ros-jazzy-simulation-interfaces`` or ``ros-jazzy-tf2-msgs``
must see the same type hashes as the node advertises (rmw_zenoh puts them in its key
expressions). The pinned values are upstream's: simulation_interfaces tag 1.5.1 (a3c60ff)
and geometry2 jazzy, through Jazzy's rosidl 4.6.6. The message and service hashes are those of
../shared/ros-review-2.md §3.5; SimulateSteps' were computed from the upstream
``action/SimulateSteps.action`` of tag 1.5.1 (with its ``msg/Result.msg``) by rosidl's
type-description generator in a scratch CMake package, outside this repository's build.
The installed interface descriptions (``share/<package>/<kind>/<Type>.json``, what the
type support was generated from) are compared, whichever build installed them.
"""

import json
from pathlib import Path

import pytest
from ament_index_python.packages import get_package_share_directory

from rigid_rot_sim.share import ensure_ament_prefix_path

UPSTREAM_HASHES = {
    "simulation_interfaces/msg/Result": "cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17",
    "simulation_interfaces/msg/SimulationState": "bb9f87ccdd98fba113052a512d9801e84ce732d0a2b3c2b0cb281828de36e415",
    "simulation_interfaces/msg/SimulatorFeatures": "8b101c8529bc0ea3dcf056078254768f39832b9ef0adaf93bd5cea96c0de3305",
    "simulation_interfaces/srv/GetSimulationState": "3362dcebee4b1afebbf9c4beee5c79c1455385aded62092a892d61fde8644f30",
    "simulation_interfaces/srv/GetSimulatorFeatures":
        "abb9439c8cf196722a469fb6c68b44b484f198c2a1356ac38849a29c2a20a794",
    "simulation_interfaces/srv/ResetSimulation": "4ce285d7ff9b8ac70dcc95161f32bf54c05a6f4b13427990e41ab40c36c39646",
    "simulation_interfaces/srv/SetSimulationState": "a868b916dce49974f637ba252141258c4b07b0c06858b88af560e3eb6bfbcb30",
    "simulation_interfaces/srv/StepSimulation": "913fe0653690ce6bf8f09f316e6a626747012e9fca31e26719910d417aa8565c",
    "simulation_interfaces/action/SimulateSteps": "f0837c898e1219cd73bf4c041feab41e8c533e8e1057e982744dba7b093467eb",
    "simulation_interfaces/action/SimulateSteps_Goal":
        "3f02c5df1dcdc7c08efee7f47c953c42c11686e0df8f8bbfb2d7e901f0d440d2",
    "simulation_interfaces/action/SimulateSteps_Result":
        "a1384eaee4ca7ae9238e612dfe26939dd0922cae664be1b5886cf773718823dc",
    "simulation_interfaces/action/SimulateSteps_Feedback":
        "735661ca01115eb9bca068c3f2cb79bd790cd46962317ce7ee9081a5915c9a77",
    "simulation_interfaces/action/SimulateSteps_FeedbackMessage":
        "a30dee7ee7380769e616406ec5067b238aa2b27e1dbd7a5957fba1d908d7754d",
    "simulation_interfaces/action/SimulateSteps_SendGoal":
        "504407b9ff5617a737df8222cf581452b4f2e699e11e940d8d36590c5fb07d01",
    "simulation_interfaces/action/SimulateSteps_SendGoal_Request":
        "275e6fd2fafc5d33dcdc83bdea6de5cf29f30b9df74a3b9514a8c5d501fd0fe3",
    "simulation_interfaces/action/SimulateSteps_SendGoal_Response":
        "755f44a68d1e8d116f50dfed7ab30a140137fb71ad59eca4851d55abe2b3d4c2",
    "simulation_interfaces/action/SimulateSteps_GetResult":
        "a1dae0516ab5c70d6d797e1bcd55c9448dfbb1966643f1ebd3e3f153d8169ae0",
    "simulation_interfaces/action/SimulateSteps_GetResult_Request":
        "4591b0bfbcb881003bbd46a2acebcaddceb977e5352905218688ce5ed051fdeb",
    "simulation_interfaces/action/SimulateSteps_GetResult_Response":
        "5658172e771cb145a986a8ef4c2b80b5407b741038453b8539e35bed5ff23207",
    "tf2_msgs/msg/TFMessage": "e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
}


def _installed_hashes(type_name: str) -> dict[str, str]:
    """Every type hash in the installed description file that describes ``type_name``."""
    ensure_ament_prefix_path()  # the venv as the console scripts see it, without activation
    package, kind, name = type_name.split("/")
    top = name.split("_")[0] if kind == "action" else name
    path = Path(get_package_share_directory(package)) / kind / f"{top}.json"
    described = json.loads(path.read_text(encoding="utf-8"))
    return {entry["type_name"]: entry["hash_string"] for entry in described["type_hashes"]}


@pytest.mark.parametrize("type_name", sorted(UPSTREAM_HASHES))
def test_installed_interfaces_have_the_upstream_type_hash(type_name):
    assert _installed_hashes(type_name)[type_name] == "RIHS01_" + UPSTREAM_HASHES[type_name]


def test_the_action_type_imports_with_the_upstream_fields():
    from simulation_interfaces.action import SimulateSteps

    assert SimulateSteps.Goal().steps == 0 and SimulateSteps.Goal.get_fields_and_field_types() == {"steps": "uint64"}
    assert SimulateSteps.Feedback.get_fields_and_field_types() == {
        "completed_steps": "uint64", "remaining_steps": "uint64"}
    assert SimulateSteps.Result.get_fields_and_field_types() == {"result": "simulation_interfaces/Result"}
