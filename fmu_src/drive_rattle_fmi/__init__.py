"""FMI layer of the drive-rattle FMUs (pythonfmu slaves, modelDescription, native status shim)."""
