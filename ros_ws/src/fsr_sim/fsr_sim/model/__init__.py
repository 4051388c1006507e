"""The flight model from plain Python values: vehicles, surfaces, disturbances, the plant (no ROS, no YAML).

    from fsr_sim.model import Plant, load_vehicle
    plant = Plant(load_vehicle("quadrotor_ex4"), dt=0.001, actuation="wrench", position=[0, 0, -1])
    plant.set_wrench(force_body=[0, 0, -11.772], torque_body=[0, 0, 0])
    plant.step()
    plant.state.position, plant.state.rotation

Modules: :mod:`~fsr_sim.model.frames` (NED/FRD), :mod:`~fsr_sim.model.so3` (rotations),
:mod:`~fsr_sim.model.vehicle`, :mod:`~fsr_sim.model.rotors` (the rotors' wrench, limits and saturation record),
:mod:`~fsr_sim.model.environment`, :mod:`~fsr_sim.model.disturbances`, :mod:`~fsr_sim.model.rigid_body`,
:mod:`~fsr_sim.model.plant`. What the controller derives from the model (the allocation, the authority, the
designed gains) is in :mod:`fsr_control`.
Importing this package imports no rclpy and reads no YAML (``load_vehicle`` reads its file on call); the
per-step models are the compiled core of :mod:`fsr_sim.core`.
"""

from fsr_sim.model import disturbances
from fsr_sim.model.environment import Environment, Surface
from fsr_sim.model.frames import E3
from fsr_sim.model.plant import Plant
from fsr_sim.model.rigid_body import RigidBodyState
from fsr_sim.model.vehicle import Vehicle, load_vehicle

__all__ = ["E3", "Environment", "Plant", "RigidBodyState", "Surface", "Vehicle", "disturbances",
           "load_vehicle"]
