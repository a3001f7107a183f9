"""The readable equations: an independent oracle of the model library (not shipped).

The paper's geometry (geometry.py), Hertz contact and Hunt-Crossley dissipation (hertz.py), the
pair's load-approach laws (approach.py: Hertz, Palmgren's line contact, the Greenwood-Tripp
asperity layer in series), film and friction (lubrication.py) and the mesh loads they make
(mesh.py), in plain Python on SI floats, with Brent's method (roots.py); and the monolithic
scipy reference of the coupled system (reference.py), whose forces come from this oracle.
tests/model holds the library's probes, units and co-simulation against them with tolerances.
Nothing here steps the wheel: the stepper is tested through its results (closed forms,
properties, the reference).

Only the reference reads the library (the co-simulation's start state); the equations import
nothing but the standard library.
"""
