"""Control laws returning a body wrench (:class:`~fsr_control.controllers.common.ControlLaw`): geometric
(fixed rotors), Voliro (tilting rotors) and INDI (fixed rotors, on the IMU and the rotors' measured speeds)."""

from fsr_control.controllers.common import ControlLaw, WrenchCommand
from fsr_control.controllers.geometric import GeometricController
from fsr_control.controllers.indi import IndiController
from fsr_control.controllers.voliro import VoliroController

__all__ = ["ControlLaw", "GeometricController", "IndiController", "VoliroController", "WrenchCommand"]
