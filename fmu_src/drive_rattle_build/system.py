"""The system file of the build: ``DriveRattle.ssp`` next to the FMUs."""

from __future__ import annotations

import tempfile
import zipfile
from pathlib import Path

from drive_rattle.interface import DRIVELINE, MESH

from .compiler import BuildError

#: The system file written next to the FMUs.
SYSTEM_NAME = "DriveRattle.ssp"


def write_system(fmus: list[Path], out_dir: Path) -> Path:
    """``out_dir/DriveRattle.ssp``: both FMUs, their connections, every parameter at its
    default and every input's start value at what its partner outputs at the start (so it
    also runs in masters that exchange nothing during initialization), at the FMUs' default
    experiment; validated against the SSP 1.0 schema."""
    from fmpy import read_model_description

    from drive_rattle_cosim.ssp import SSD_NAME, default_parameters, validate_ssd, write_ssp

    by_name = {Path(p).stem: Path(p) for p in fmus}
    experiment = read_model_description(str(by_name[MESH])).defaultExperiment
    path = write_ssp(Path(out_dir) / SYSTEM_NAME, by_name[MESH], by_name[DRIVELINE],
                     default_parameters(by_name), step=float(experiment.stepSize),
                     start_time=float(experiment.startTime),
                     stop_time=float(experiment.stopTime), input_starts="consistent")
    with tempfile.TemporaryDirectory() as tmp, zipfile.ZipFile(path) as z:
        z.extract(SSD_NAME, tmp)
        try:
            validate_ssd(Path(tmp) / SSD_NAME)
        except Exception as err:
            raise BuildError(f"{path.name}: the SSD is not valid SSP 1.0: {err}") from None
    return path
