"""The system files of the build: ``DriveRattle.ssp`` and ``DriveRattle_outputs.ssp`` next to
the FMUs.  Their FMUs are the FMUs of the build with the integer codes declared Integers
(``drive_rattle_cosim.variants.integer_codes``; the same binaries), so that libcosim and ecos,
which ignore FMI 2.0 Enumeration variables, load them with no warning and apply every binding;
each bundled FMU is validated as the build's own are."""

from __future__ import annotations

import tempfile
import zipfile
from pathlib import Path

from drive_rattle.interface import DRIVELINE, MESH

from .compiler import BuildError

#: The system file written next to the FMUs: runs in every SSP master measured (libcosim,
#: ecos, fmpy's SSP runner, fmu-manipulation-toolbox's container), with every binding applied
#: (ecos: when the set is named; fmpy's SSP runner and the container: by the project's runners).
SYSTEM_NAME = "DriveRattle.ssp"
#: The same system with every output of both units also a system output, for masters that
#: expose or record only system connectors (fmu-manipulation-toolbox's container); libcosim
#: and ecos refuse an SSD with connections to system connectors.
SYSTEM_OUTPUTS_NAME = "DriveRattle_outputs.ssp"


def write_system(fmus: list[Path], out_dir: Path, system_outputs: bool = False,
                 use_fmutool: bool = False) -> Path:
    """``out_dir/DriveRattle.ssp`` (``DriveRattle_outputs.ssp`` with ``system_outputs``):
    both FMUs with their integer codes declared Integers, their connections, one parameter set
    per component with every parameter at its default and every input's start value at what
    its partner outputs at the start (so it also runs in masters that exchange nothing during
    initialization), at the FMUs' default experiment; the SSD validated against the SSP 1.0
    schema, each bundled FMU with fmpy's ``validate_fmu`` (and ``fmutool -check`` with
    ``use_fmutool``)."""
    from fmpy import read_model_description

    from drive_rattle_cosim.ssp import SSD_NAME, default_parameters, validate_ssd, write_ssp

    from .fmu import validate

    by_name = {Path(p).stem: Path(p) for p in fmus}
    experiment = read_model_description(str(by_name[MESH])).defaultExperiment
    name = SYSTEM_OUTPUTS_NAME if system_outputs else SYSTEM_NAME
    path = write_ssp(Path(out_dir) / name, by_name[MESH], by_name[DRIVELINE],
                     default_parameters(by_name), step=float(experiment.stepSize),
                     start_time=float(experiment.startTime),
                     stop_time=float(experiment.stopTime), input_starts="consistent",
                     system_outputs=system_outputs)
    with tempfile.TemporaryDirectory() as tmp, zipfile.ZipFile(path) as z:
        z.extractall(tmp)
        try:
            validate_ssd(Path(tmp) / SSD_NAME)
        except Exception as err:
            raise BuildError(f"{path.name}: the SSD is not valid SSP 1.0: {err}") from None
        for bundled in sorted(Path(tmp, "resources").glob("*.fmu")):
            try:
                validate(bundled, use_fmutool)
            except BuildError as err:
                raise BuildError(f"{path.name}: resources/{err}") from None
    return path


def write_systems(fmus: list[Path], out_dir: Path, use_fmutool: bool = False) -> list[Path]:
    """Both system files (``write_system`` without and with system outputs)."""
    return [write_system(fmus, out_dir, use_fmutool=use_fmutool),
            write_system(fmus, out_dir, system_outputs=True, use_fmutool=use_fmutool)]
