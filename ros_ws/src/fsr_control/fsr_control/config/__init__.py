"""Validation of fsr_control's scenario sections (``controller``, ``trajectory``)."""

from fsr_control.config.controller_config import ControllerConfig, controller_config

__all__ = ["ControllerConfig", "controller_config"]
