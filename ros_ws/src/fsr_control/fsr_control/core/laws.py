"""The control laws per step (compiled core): which law the controller's tick runs, and its parameters.

:func:`control_law` is the interface the controller's tick calls: the law ``params.kind`` names, given the
reference at ``t``, the reference over the law's horizon (``params.horizon_steps`` rows at ``t + dt, ...,
t + N dt``, ``dt = params.horizon_dt``, laid out as in :mod:`fsr_control.core.reference`; no rows for a law
that does not look ahead), the state, the compensation and the law's own memory; :func:`law_allocated`
tells it, after the allocation, what of its wrench the rotors could not produce.

A law's parameters are its own: a NamedTuple in the law's core file (:class:`GeometricParams`,
:class:`VoliroParams`, :class:`IndiParams`), held in its field of :class:`LawParams` (the other laws' fields hold
placeholders, so that one compiled tick serves every law); its memory is its own record (a 1-element numpy record
array whose fields it reads and writes as ``memory.geometric[0].integral``), a field of :class:`LawMemory` (every
controller holds every law's, for the same reason). A new law is its core file (its function, its parameters
with an ``unused()`` placeholder, its memory's record type if it keeps any), an import, a field and a branch
here, and an entry in
:data:`fsr_control.controllers.catalog.LAWS` (``docs/extending.md``).

Each law takes the reference, the state (:class:`VehicleState`: position and velocity world NED [m, m/s], ``R``
rows body FRD -> world, angular velocity body [rad/s]), a law on the vehicle's own measurements what it measured of
the state's stamp (:class:`Measured`) and, with ``controller.compensation: estimate``, the estimated external wrench
to cancel (:class:`Compensation`), and returns ``(status, force_body, torque_body, R_c)``: the body wrench
[N, N m] to produce and the attitude the law steers to. Their equations and the reasons behind them are in
:mod:`fsr_control.controllers.geometric`, :mod:`fsr_control.controllers.voliro` and
:mod:`fsr_control.controllers.indi` (the Python shells).
"""

from __future__ import annotations

from typing import NamedTuple, get_type_hints

import numpy as np

from fsr_control.core.geometric_law import (
    GEOMETRIC_MEMORY,
    GeometricParams,
    flown_state,
    geometric_allocated,
    geometric_law,
)
from fsr_control.core.imu_bridge import BRIDGE_MEMORY
from fsr_control.core.indi_law import INDI_MEMORY, IndiParams, indi_allocated, indi_law
from fsr_control.core.law_terms import NO_COMPENSATION, Compensation, Measured, VehicleState, linear_feedback
from fsr_control.core.reference import ReferenceSample
from fsr_control.core.voliro_law import VoliroParams, voliro_law
from fsr_sim.core.jit import jit_inline, zeroed_record
from fsr_sim.core.so3 import Vec3

__all__ = ["NO_COMPENSATION", "Compensation", "LawMemory", "LawParams", "Measured", "VehicleState", "control_law",
           "law_allocated", "law_params", "linear_feedback", "new_law_memory", "reset_law_memory"]


class LawParams(NamedTuple):
    kind: int  # which law: the index of its field below (GEOMETRIC, VOLIRO, ...)
    horizon_steps: int  # reference samples ahead the law reads (0: none)
    horizon_dt: float  # their spacing [s]
    geometric: GeometricParams
    voliro: VoliroParams
    indi: IndiParams
    # a new law: its parameters here, e.g. ``my_law: MyLawParams``


LAW_FIELDS = LawParams._fields[3:]  # the laws, in the order of their kinds
GEOMETRIC, VOLIRO, INDI = LAW_FIELDS.index("geometric"), LAW_FIELDS.index("voliro"), LAW_FIELDS.index("indi")


class LawMemory(NamedTuple):
    """What the laws keep between steps: each a 1-element record array of its core file's record type."""

    geometric: np.ndarray  # GEOMETRIC_MEMORY (fsr_control.core.geometric_law)
    bridge: np.ndarray  # BRIDGE_MEMORY: the IMU-bridged estimate the geometric law and INDI fly on (imu_bridge)
    indi: np.ndarray  # INDI_MEMORY (fsr_control.core.indi_law)
    # a new law that keeps anything: its record here, e.g. ``my_law: np.ndarray  # MY_LAW_MEMORY``


MEMORY_TYPES = {"geometric": GEOMETRIC_MEMORY, "bridge": BRIDGE_MEMORY, "indi": INDI_MEMORY}  # LawMemory's fields


def new_law_memory() -> LawMemory:
    """Every law's memory, zeroed (nothing seen yet)."""
    return LawMemory(**{name: zeroed_record(record) for name, record in MEMORY_TYPES.items()})


def reset_law_memory(memory: LawMemory) -> None:
    """Forget everything the laws kept (as :func:`new_law_memory`)."""
    for record in memory:
        record[...] = 0


def law_params(kind: int, own: NamedTuple, horizon_steps: int = 0, horizon_dt: float = 0.0) -> LawParams:
    """The tick's :class:`LawParams` for the law ``kind`` with its parameters ``own``; every other law's field
    holds its parameters' ``unused()`` placeholder (the same types, so one compiled tick serves every law)."""
    types = get_type_hints(LawParams)
    if not 0 <= kind < len(LAW_FIELDS) or type(own) is not types[LAW_FIELDS[kind]]:
        raise ValueError(f"a law's kind is the place of its parameters among LawParams' laws {LAW_FIELDS}: kind "
                         f"{kind} does not hold {type(own).__name__}")
    fields = {name: (own if index == kind else types[name].unused()) for index, name in enumerate(LAW_FIELDS)}
    return LawParams(kind, int(horizon_steps), float(horizon_dt), **fields)


@jit_inline
def control_law(params: LawParams, memory: LawMemory, horizon, t: float, reference: ReferenceSample,  # noqa: ANN001
                state: VehicleState, compensation: Compensation, measured: Measured) -> tuple:
    """``(status, force_body, torque_body, R_c)`` of the law ``params.kind`` (module docstring): ``memory`` the
    laws' (:class:`LawMemory`), ``horizon`` the reference ahead (``params.horizon_steps`` rows); ``measured``
    what the vehicle measures of the same stamp as ``state`` (read only by a law that needs it)."""
    if params.kind == VOLIRO:
        return voliro_law(params.voliro, reference, state, compensation)
    if params.kind == INDI:
        return indi_law(params.indi, memory, t, reference, state, measured)
    # a new law: its branch here, e.g. ``if params.kind == MY_LAW: return my_law(params.my_law, horizon, ...)``
    flown = flown_state(params.geometric, memory.bridge[0], state, measured.imu)
    return geometric_law(params.geometric, memory.geometric[0], t, reference, flown, compensation)


@jit_inline
def law_allocated(params: LawParams, memory, force: Vec3, torque: Vec3, shortfall) -> None:  # noqa: ANN001
    """After the allocation of the law's wrench: ``force``, ``torque`` the body wrench its command produces
    [N, N m], ``shortfall`` (6,) the demanded minus that (what a law with an integral needs for its
    anti-windup)."""
    if params.kind == GEOMETRIC:
        geometric_allocated(params.geometric, memory.geometric[0], shortfall)
    elif params.kind == INDI:
        indi_allocated(params.indi, memory, force, torque, shortfall)
