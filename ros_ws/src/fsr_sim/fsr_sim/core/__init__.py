"""The compiled flight core of the plant side (:mod:`fsr_sim.core.jit`): rotations, rigid body, rotors,
surfaces, disturbances, the plant, the published state and the lockstep step."""
