"""Driveline: the simple driveline around the gear mesh as an FMI 2.0 co-simulation slave --
input-shaft kinematics from engine orders or a measured speed table, and the output shaft to
the reflected vehicle inertia.  Thin: the model is the library (fmu_src/rattle_model), the FMI
face drive_rattle_fmi; this module only names the unit and describes it.

The class is made once per process by ``slave_class`` (pythonfmu executes this module anew at
every instantiation: it must define no class of its own; drive_rattle_fmi/slave.py)."""

from drive_rattle_fmi.slave import slave_class

Driveline = slave_class(
    "Driveline",
    description=(
        "Driveline around the drive-rattle gear mesh: input-shaft kinematics from engine orders "
        "or a measured speed table, output shaft as a torsional spring-damper to a reflected "
        "vehicle inertia with drag"),
    doc=("Engine-order (or measured) pinion kinematics out; wheel angle and speed in, "
         "output-shaft load torque out."))
