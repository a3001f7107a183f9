"""The readable equations: an independent oracle of the model library (not shipped).

Each module mirrors the model library's source file of the same name (fmu_src/rattle_model):
the paper's geometry (geometry.py), the pair's contact -- Hertz, Palmgren's line contact, the
Greenwood-Tripp asperity layer in series and Hunt-Crossley's dissipation (contact.py) -- the
dissipation set at each onset (dissipation.py), film and friction (friction.py) and the mesh
loads they make (mesh.py), in plain Python on SI floats, with Brent's method (roots.py); and
the monolithic scipy reference of the coupled system (reference.py, the oracle of system.c),
whose forces come from this oracle.  tests/model/test_<room>.py holds the library's probes,
units and co-simulation against the oracle of the same name with tolerances.
Nothing here steps the wheel: the stepper is tested through its results (closed forms,
properties, the reference).

Only the reference reads the library (the co-simulation's start state); the equations import
nothing but the standard library.
"""
