"""Control laws returning a body wrench (:class:`~fsr_control.controllers.common.ControlLaw`): geometric
(fixed rotors) and Voliro (tilting rotors)."""

from fsr_control.controllers.common import ControlLaw, WrenchCommand
from fsr_control.controllers.geometric import GeometricController
from fsr_control.controllers.voliro import VoliroController

__all__ = ["ControlLaw", "GeometricController", "VoliroController", "WrenchCommand"]
