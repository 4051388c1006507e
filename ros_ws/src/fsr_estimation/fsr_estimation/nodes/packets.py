"""The estimator's per-step messages as packed CDR bytes (the node publishes them; an in-process recording
writes them): ``wrench_estimate`` (WrenchStamped, ``base_link_frd``, the pair's stamp) and ``mass_estimate``
(Float64 [kg]): the estimate's body-frame force [N] and torque [N m] and its mass [kg]."""

from __future__ import annotations

from fsr_estimation.estimator.stamped import Estimate
from fsr_sim.contract import MASS_ESTIMATE, WRENCH_ESTIMATE
from fsr_sim.ros import cdr_pack


class EstimatePackets:
    """Packs an :class:`Estimate` into the CDR payloads of ``wrench_estimate`` and ``mass_estimate``."""

    def __init__(self) -> None:
        self._wrench = cdr_pack.wrench_stamped(WRENCH_ESTIMATE.frame)
        self._mass = cdr_pack.float64()
        self.templates = {WRENCH_ESTIMATE.name: self._wrench, MASS_ESTIMATE.name: self._mass}  # topic -> template

    def pack(self, estimate: Estimate) -> tuple[bytes, bytes]:
        wrench, mass = self.values(estimate)
        return self._wrench.pack(estimate.stamp_ns, wrench), self._mass.pack(0, mass)

    @staticmethod
    def values(estimate: Estimate) -> tuple[tuple[float, ...], tuple[float]]:
        """The numbers of ``wrench_estimate`` (force, torque body) and ``mass_estimate`` [kg]."""
        return (*estimate.force_body.tolist(), *estimate.torque_body.tolist()), (float(estimate.mass),)
