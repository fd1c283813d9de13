"""Independent reference solutions used to verify the towenv simulator.

Nothing in this subpackage imports the simulator itself: the closed forms in
:mod:`towenv.verification.closed_forms` are written from first principles with
numpy/scipy only, so that agreement with the simulator is evidence rather than
a tautology.  See ``shared/reference/verification.md`` (cases V1-V7).
"""
