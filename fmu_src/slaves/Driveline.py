"""Driveline: the simple driveline around the gear mesh as an FMI 2.0 co-simulation slave --
input-shaft kinematics from engine orders or a measured speed table, and the output shaft to
the reflected vehicle inertia.  Thin: the model is the library (fmu_src/rattle_model), the FMI
face drive_rattle_fmi; this module only names the unit and describes it.

pythonfmu executes this module anew at every instantiation: it defines no class of its own
(``slave_class`` makes it once per process) and holds the reference to its namespace that
pythonfmu then releases (``hold_namespace``; drive_rattle_fmi/slave.py)."""

from drive_rattle_fmi.slave import hold_namespace, slave_class

hold_namespace(globals())

Driveline = slave_class("Driveline")
