"""GearMeshRattle: the gear-mesh impact and flank-friction model (Theodossiades et al. 2008) as
an FMI 2.0 co-simulation slave.  Thin: the model is the library (fmu_src/rattle_model), the
FMI face drive_rattle_fmi; this module only names the unit and describes it.

pythonfmu executes this module anew at every instantiation: it defines no class of its own
(``slave_class`` makes it once per process) and holds the reference to its namespace that
pythonfmu then releases (``hold_namespace``; drive_rattle_fmi/slave.py)."""

from drive_rattle_fmi.slave import hold_namespace, slave_class

hold_namespace(globals())

GearMeshRattle = slave_class("GearMeshRattle")
