"""The MuJoCo model of a testbed plant: the project's MJCF export with the plant's effects written in.

Built on :func:`csjm_opt.model.mjcf.rig_to_mjcf` of the plant's *true* rig
(hole offsets, mass/centre of mass and stiffness errors are already in it),
edited as an XML tree:

* each tendon ``cable<i>`` gets ``frictionloss = F_i`` (the plant's Coulomb
  friction at the guide; a capstan law is realised at run time by
  :mod:`csjm_opt.testbed.mujoco.plant` as a tension-proportional
  ``frictionloss``);
* the ball joint gets ``frictionloss`` (the plant's joint friction, per axis
  of {A});
* with a link compliance the mass, centre of mass and inertia move to a
  second body ``tool`` (frame {A_m}, the body the tracker, the load and the
  F/T sensor sit on), joined to ``platform`` by a ball joint ``link`` at O;
  its spring (the compliance matrix's inverse) is applied at run time. The
  platform keeps a negligible mass at O (no weight moment) and the inertia
  (for the dynamics only);
* ``noslip_iterations`` (MuJoCo's soft friction creeps without them), the
  damping of the joints, the keyframe removed (the plant sets ``qpos``).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from ...model.dynamics import rig_dynamics
from ...model.mjcf import rig_to_mjcf
from ..plant import TestbedPlant

#: Mass (kg) left on the cable platform when the load sits on a compliant tool.
PLATFORM_MASS_KG = 1e-6


def plant_mjcf(plant: TestbedPlant, rest_lengths_m: np.ndarray, joint_damping_Nms_per_rad: float,
               timestep_s: float = 1e-3, integrator: str = "implicitfast",
               noslip_iterations: int = 30) -> str:
    """MJCF text of ``plant`` (see the module doc).

    Parameters
    ----------
    plant : TestbedPlant
        The true rig and its injected effects.
    rest_lengths_m : (m,) array
        Initial rest lengths (changed at run time through ``tendon_lengthspring``).
    joint_damping_Nms_per_rad : float
        Damping of the ball joint and of the link (settling).
    timestep_s : float, optional
    integrator : str, optional
        MuJoCo integrator.
    noslip_iterations : int, optional
        Iterations of MuJoCo's noslip solver (stops frictional creep).

    Returns
    -------
    str
        The MJCF document.
    """
    rig = plant.rig
    xml = rig_to_mjcf(rig, rest_lengths_m, joint_damping_Nms_per_rad=joint_damping_Nms_per_rad,
                      timestep_s=timestep_s, integrator=integrator, model_name="csjm_testbed")
    root = ET.fromstring(xml)
    option = root.find("option")
    assert option is not None
    option.set("noslip_iterations", str(int(noslip_iterations)))
    for key in root.findall("keyframe"):
        root.remove(key)
    F = np.asarray(plant.friction_coulomb_N, float)
    for i, tendon in enumerate(root.iter("spatial")):
        tendon.set("frictionloss", repr(float(F[i])))
    body = root.find("worldbody/body[@name='platform']")
    assert body is not None
    ball = body.find("joint")
    assert ball is not None
    if plant.joint_friction_Nm > 0:
        ball.set("frictionloss", repr(float(plant.joint_friction_Nm)))
    if has_link(plant):
        inertial = body.find("inertial")
        assert inertial is not None
        body.remove(inertial)
        I = rig_dynamics(rig).inertia_com_A_kgm2
        light = ET.Element("inertial", {"pos": "0 0 0", "mass": repr(PLATFORM_MASS_KG),
                                        "fullinertia": " ".join(repr(float(x)) for x in
                                                                [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2],
                                                                 I[1, 2]])})
        body.insert(1, light)
        tool = ET.SubElement(body, "body", {"name": "tool", "pos": "0 0 0"})
        ET.SubElement(tool, "joint", {"name": "link", "type": "ball", "pos": "0 0 0",
                                      "damping": repr(float(joint_damping_Nms_per_rad))})
        tool.append(inertial)
    return ET.tostring(root, encoding="unicode")


def has_link(plant: TestbedPlant) -> bool:
    """Whether the plant has a compliant link between the cable platform and the tool.

    Parameters
    ----------
    plant : TestbedPlant

    Returns
    -------
    bool
    """
    return bool(np.any(np.asarray(plant.link_compliance_rad_per_Nm) != 0))
