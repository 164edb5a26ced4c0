"""Locate robot files shipped by example-robot-data and build Pinocchio models from them.

Only paths and the Pinocchio kinematic/inertial model come from here; the actuator numbers
(torque limits, armature) are set by each robot's module, since the URDFs' values are
placeholders.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import example_robot_data
import pinocchio as pin

from wbmpc.errors import ParameterError

ROOT_JOINT_NAME = "root_joint"
"""Name of the free-flyer joint added at the root (the one example-robot-data uses)."""


@dataclasses.dataclass(frozen=True)
class UrdfFiles:
    """Files of one robot in example-robot-data.

    Attributes:
        urdf_path: the URDF.
        srdf_path: the SRDF (reference postures), or None.
        package_dirs: directories resolving ``package://example-robot-data/...`` mesh paths.
        robot_dir: the robot's folder (``.../robots/<robot>_description``).
    """

    urdf_path: Path
    srdf_path: Path | None
    package_dirs: tuple[Path, ...]
    robot_dir: Path


def example_robot_data_files(description_dir: str, urdf_subpath: str, srdf_subpath: str | None = None) -> UrdfFiles:
    """Locate a robot's URDF/SRDF in the installed example-robot-data.

    Args:
        description_dir: folder under ``robots/``, e.g. "bolt_description".
        urdf_subpath: URDF path inside that folder, e.g. "robots/bolt.urdf".
        srdf_subpath: SRDF path inside that folder, or None.
    """
    relative = f"{description_dir}/{urdf_subpath}"
    try:
        models_dir = Path(example_robot_data.getModelPath(relative)).resolve()
    except OSError as err:
        raise ParameterError(f"example-robot-data does not provide {relative!r}: {err}") from None
    robot_dir = models_dir / description_dir
    srdf_path = robot_dir / srdf_subpath if srdf_subpath else None
    if srdf_path is not None and not srdf_path.is_file():
        raise ParameterError(f"SRDF {srdf_path} not found in example-robot-data")
    # package://example-robot-data/robots/... resolves against the folder holding "example-robot-data".
    return UrdfFiles(
        urdf_path=robot_dir / urdf_subpath,
        srdf_path=srdf_path,
        package_dirs=(models_dir.parent.parent, models_dir),
        robot_dir=robot_dir,
    )


def build_floating_base_model(files: UrdfFiles) -> pin.Model:
    """Pinocchio model of the URDF with a free-flyer root joint named ``ROOT_JOINT_NAME``.

    SRDF reference configurations (if any) are loaded into ``model.referenceConfigurations``.
    No mesh is loaded (kinematics and inertias only).
    """
    model = pin.buildModelFromUrdf(str(files.urdf_path), pin.JointModelFreeFlyer(), ROOT_JOINT_NAME)
    if files.srdf_path is not None:
        pin.loadReferenceConfigurations(model, str(files.srdf_path), False)
    return model
