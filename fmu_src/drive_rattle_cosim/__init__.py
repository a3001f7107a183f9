"""Co-simulation tooling around the drive-rattle FMUs: the fmpy harness, the SSP system for
libcosim, the regression kit for exported FMUs and parameter sweeps."""
