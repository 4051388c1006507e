"""What the controller designs from the vehicle's model, once at start-up (not per step): the authority of its
rotors at hover (:mod:`~fsr_control.design.authority`, kept per vehicle by
:mod:`~fsr_control.design.authority_cache`) and the loop gains designed from it
(:mod:`~fsr_control.design.gain_design`). Nothing is imported here (the authority imports scipy)."""
