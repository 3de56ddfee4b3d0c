"""The Franka Panda URDF of example-robot-data, reduced to the 7-DoF arm ending at the flange.

The shipped file ``panda_description/urdf/panda.urdf`` describes the arm (``panda_link0`` …
``panda_link8``, the flange) and the Franka gripper (``panda_hand``, its TCP and two fingers). ccopt
mounts a flat hand plate on the flange instead, so :func:`arm_urdf` removes every link below
``panda_link8`` and the joints leading to them, and rewrites the ``package://`` mesh URIs to absolute
file paths so that Pinocchio and MuJoCo can both read the result without a ROS package path.
"""

from __future__ import annotations

import functools
import importlib.metadata
import xml.etree.ElementTree as ET
from pathlib import Path

FLANGE_LINK = "panda_link8"
"""The arm's last link: the flange (ISO 9409 mounting face), 0.107 m past joint 7 along its axis."""

ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
"""The seven revolute joints, base to wrist."""

_DISTRIBUTION = "example-robot-data"
_ROBOT_DIR = "share/example-robot-data/robots/panda_description"
_PACKAGE_PREFIX = "package://example-robot-data/robots/panda_description/"


def panda_description_dir() -> Path:
    """Directory ``panda_description`` installed by the ``example-robot-data`` distribution.

    Found through the distribution's file list, so no install prefix is assumed.
    Raises ``FileNotFoundError`` when the distribution or its Panda URDF is missing.
    """
    try:
        files = importlib.metadata.distribution(_DISTRIBUTION).files or []
    except importlib.metadata.PackageNotFoundError as err:
        raise FileNotFoundError(f"the '{_DISTRIBUTION}' distribution is not installed") from err
    for file in files:
        if file.as_posix().endswith(f"{_ROBOT_DIR}/urdf/panda.urdf"):
            return Path(file.locate()).resolve().parent.parent
    raise FileNotFoundError(f"'{_DISTRIBUTION}' ships no {_ROBOT_DIR}/urdf/panda.urdf")


def _descendant_links(root: ET.Element, link: str) -> set[str]:
    """Names of all links below ``link`` in the kinematic tree (``link`` excluded)."""
    children: dict[str, list[str]] = {}
    for joint in root.iter("joint"):
        children.setdefault(joint.find("parent").get("link"), []).append(joint.find("child").get("link"))
    found: set[str] = set()
    stack = list(children.get(link, []))
    while stack:
        name = stack.pop()
        found.add(name)
        stack.extend(children.get(name, []))
    return found


@functools.cache
def arm_urdf(visuals: bool = False) -> str:
    """URDF text of the 7-DoF Panda arm ending at the flange ``panda_link8``.

    The gripper links and joints below the flange are removed, mesh URIs point to absolute paths
    (the ``.stl`` collision meshes; the ``.dae`` visuals are kept only if ``visuals`` is true, since
    MuJoCo cannot read them). Inertial data, joint limits and frames are those of example-robot-data.
    """
    directory = panda_description_dir()
    root = ET.parse(directory / "urdf" / "panda.urdf").getroot()
    removed = _descendant_links(root, FLANGE_LINK)
    links = [link for link in root.findall("link") if link.get("name") in removed]
    joints = [joint for joint in root.findall("joint") if joint.find("child").get("link") in removed]
    for element in links + joints:
        root.remove(element)
    if not visuals:
        for link in root.iter("link"):
            for visual in link.findall("visual"):
                link.remove(visual)
    for mesh in root.iter("mesh"):
        uri = mesh.get("filename", "")
        if uri.startswith(_PACKAGE_PREFIX):
            mesh.set("filename", str(directory / uri.removeprefix(_PACKAGE_PREFIX)))
    return ET.tostring(root, encoding="unicode")
