"""The estimator's per-step messages as packed CDR bytes (the node publishes them; an in-process recording
writes them): ``wrench_estimate`` (WrenchStamped, ``base_link_frd``, the pair's stamp) and ``mass_estimate``
(Float64 [kg]): the estimate's body-frame force [N] and torque [N m] and its mass [kg]."""

from __future__ import annotations

from fsr_estimation.core.stamped import Estimate
from fsr_sim.ros import cdr_pack

BODY_FRAME = "base_link_frd"


class EstimatePackets:
    """Packs an :class:`Estimate` into the CDR payloads of ``wrench_estimate`` and ``mass_estimate``."""

    def __init__(self) -> None:
        self._wrench = cdr_pack.wrench_stamped(BODY_FRAME)
        self._mass = cdr_pack.float64()

    def pack(self, estimate: Estimate) -> tuple[bytes, bytes]:
        wrench = self._wrench.pack(estimate.stamp_ns, (*estimate.force_body.tolist(), *estimate.torque_body.tolist()))
        return wrench, self._mass.pack(0, (float(estimate.mass),))
