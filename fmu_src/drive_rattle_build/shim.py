"""The status shim around pythonfmu's binary: build it and put it into a pythonfmu FMU.

pythonfmu 0.7.0's C++ wrapper turns any Python exception into ``fmi2Fatal`` (after which
freeing the instance corrupts the host process), ignores what the slave methods return (except
``do_step``: False gives ``fmi2Discard``), hands log messages to the host only with debug
logging on and as a printf *format* string, and checks nothing a master passes: docs/fmi.md
("The status shim") lists what crashed, leaked or corrupted the host, and how the shim stops
each.  Its sources are not shipped, so it cannot be rebuilt; the shim stands in front of it.

``fmu_src/fmi2/rattle_fmi_shim.c`` (with ``rattle_fmi_common.c`` and ``rattle_fmi2_common.c``,
which the native FMUs' glue shares) is compiled (against the official FMI 2.0 headers that
fmpy ships, :func:`fmi2_headers`) into ``binaries/linux64/<modelIdentifier>.so``; it
loads pythonfmu's library, renamed to ``<modelIdentifier>_pythonfmu.so``, from its own directory
and forwards every FMI 2.0 call to it, adding:

* the **status protocol** below, so a slave can make any FMI call return Warning, Discard,
  Error or Fatal, with its message logged to the host whether debug logging is on or not;
* **argument checks** before anything reaches pythonfmu: instance name (non-blank UTF-8),
  ``fmuType`` (co-simulation only), GUID, debug-logging categories, UTF-8 of String values,
  value references of the hidden variables; refused calls return fmi2Error (NULL) with the
  reason logged;
* the **resource location** decoded (``file://`` URIs fully percent-decoded, plain absolute
  paths) and checked (this FMU's ``slavemodule.txt`` and module); pythonfmu gets the canonical
  path, or ``/proc/self/fd/<n>`` of the opened folder where the path would be misread by it
  (a literal ``%20``, not UTF-8);
* **FMU states** owned by the shim: tagged with the GUID, reused when the host passes one
  back, freed with the instance; serialized with an envelope (GUID, version, length, FNV-1a
  checksum) around the model library's binary record and never copied past pythonfmu's
  serialization;
* status queries and unsupported functions answered with messages;
  ``fmi2LastSuccessfulTime`` from the slave's own time (``vr_last_successful_time``);
* in a native host, the **embedded interpreter started by the shim** (as ``Py_Initialize``
  would, but with the error returned) and pythonfmu's instantiation messages forced on and
  held, so that an interpreter that cannot start or a slave that cannot be imported is
  reported through the host's logger, never silently;
* pythonfmu's own log messages passed to the host as ``"%s", message`` (no format injection);
* after pythonfmu itself returned ``fmi2Fatal`` (a Python exception), no further call reaches
  it: later calls return Fatal, and ``fmi2FreeInstance`` frees only the shim's part and leaks
  pythonfmu's instance, whose second release would corrupt the process;
* **idle instances**: pythonfmu's fmi2Instantiate leaks about 1 kiB of Python objects per
  call, so fmi2FreeInstance keeps pythonfmu's instance idle (at most 8 per FMU binary) and the
  next fmi2Instantiate of the same resources folder resets it (pythonfmu's fmi2Reset makes a
  new slave object) instead of instantiating anew; pythonfmu gets the shim's calloc/free (the
  FMU declares canNotUseMemoryManagementFunctions), as an idle instance outlives the host's
  callbacks;
* an exit handler that resets pythonfmu's static Python state before its C++ static destructor
  runs (pythonfmu's ELF destructor would otherwise release it a second time at process exit:
  an invalid read under valgrind, now and then "corrupted double-linked list").  Both
  libraries stay loaded until the process ends.

Status protocol (Python side, ``drive_rattle_fmi.slave``)::

    self._fmi_status = ctypes.c_int(0)      # keep alive as long as the slave
    self._fmi_message = ""
    ...  # registered LAST, so the public value references stay 0..n-1:
    self.register_variable(String("_fmi.status_address", causality=Fmi2Causality.local,
                                  variability=Fmi2Variability.discrete,
                                  getter=lambda: hex(ctypes.addressof(self._fmi_status))),
                           nested=False)
    self.register_variable(String("_fmi.message", causality=Fmi2Causality.local,
                                  variability=Fmi2Variability.discrete,
                                  getter=lambda: self._fmi_message), nested=False)

    # to make the current FMI call return fmi2Error with a message:
    self._fmi_message = "text"              # may contain '%'
    self._fmi_status.value = 3              # 1 Warning, 2 Discard, 3 Error, 4 Fatal

and then return normally (``do_step`` returns True or False as it wishes; never raise).

The shim reads the address once after ``fmi2Instantiate`` (and again after ``fmi2Reset``,
which makes pythonfmu construct a new slave object).  After each forwarded call returning an
``fmi2Status`` it checks the int: if non-zero, it resets it to 0, reads the message, calls the
host's logger with status = the code and category ``logStatusWarning`` / ``logStatusDiscard`` /
``logStatusError`` / ``logStatusFatal``, and returns ``max(pythonfmu's status, code)``.  Codes
outside 1..4 count as Error.  An empty address string disables the protocol (pure
pass-through); the variable at ``vr_status_address`` must exist and be a String, because
pythonfmu turns the failed lookup into a Fatal (the instantiation then fails).
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree

from .compiler import compile_library
from .paths import FMI2_SOURCE, FMI_COMMON_SOURCE, MODEL_SOURCE

#: The C source of the shim.
SHIM_SOURCE: Path = FMI2_SOURCE / "rattle_fmi_shim.c"
#: What the shim shares with the native FMUs' glue (the state envelope, UTF-8), compiled with it.
COMMON_SOURCE: Path = FMI_COMMON_SOURCE / "rattle_fmi_common.c"
#: What the shim shares with the native FMI 2.0 face (fmi2Instantiate's checks, logging).
FMI2_COMMON_SOURCE: Path = FMI2_SOURCE / "rattle_fmi2_common.c"
#: The model library's operating-system layer (UTF-8, files), which rattle_fmi_common.c uses:
#: the one part of the library the shim compiles in.
PORTABLE_SOURCE: Path = MODEL_SOURCE / "portable.c"


def fmi2_headers() -> Path:
    """The folder of the official FMI 2.0 headers (``fmi2Functions.h`` and the two it
    includes), as fmpy ships them; the shim and the C test host compile against them instead
    of retyped copies."""
    import fmpy

    folder = Path(fmpy.__file__).resolve().parent / "c-code"
    if not (folder / "fmi2Functions.h").is_file():
        raise RuntimeError(f"fmpy's FMI 2.0 headers are missing: no {folder / 'fmi2Functions.h'}"
                           " (reinstall fmpy)")
    return folder

_PLATFORM_DIR = "binaries/linux64"
_INNER_SUFFIX = "_pythonfmu"
_MAX_VR = 2**32 - 1


def _check_vr(name: str, value: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= _MAX_VR:
        raise ValueError(f"{name} must be an fmi2ValueReference (0..{_MAX_VR}), got {value!r}")


def compile_shim(out_path: Path, inner_lib_name: str, vr_status_address: int, vr_message: int,
                 cc: str = "gcc", guid: str | None = None, model_identifier: str | None = None,
                 vr_last_successful_time: int | None = None) -> Path:
    """Compile the shim into ``out_path`` (a shared library) and return ``out_path``.

    ``inner_lib_name`` is the file name (no directory) of pythonfmu's library, which the shim
    loads from its own directory.  With ``guid``, fmi2Instantiate refuses any other GUID (as
    FMI 2.0 asks; pythonfmu does not check), and FMU states carry it.  With
    ``model_identifier``, the resource folder must hold that slave module.  With
    ``vr_last_successful_time`` (a hidden Real of the slave), fmi2GetRealStatus answers
    fmi2LastSuccessfulTime from the slave, else from the shim's own count of accepted steps.
    Raises RuntimeError with the compiler's output on failure.
    """
    if guid is not None and not re.fullmatch(r"[A-Za-z0-9{}-]{1,63}", guid):
        raise ValueError(f"guid must consist of letters, digits, braces and '-', got {guid!r}")
    if not re.fullmatch(r"[A-Za-z0-9_.+-]+", inner_lib_name):
        raise ValueError(f"inner_lib_name must be a plain file name, got {inner_lib_name!r}")
    if model_identifier is not None and not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,200}",
                                                         model_identifier):
        raise ValueError(f"model_identifier must be a C identifier, got {model_identifier!r}")
    _check_vr("vr_status_address", vr_status_address)
    _check_vr("vr_message", vr_message)
    if vr_last_successful_time is not None:
        _check_vr("vr_last_successful_time", vr_last_successful_time)
    flags = [
        "-std=c99", "-O2", "-Wall", "-Wextra", "-shared", "-fPIC", "-pthread",
        "-I", str(fmi2_headers()), "-I", str(FMI2_SOURCE), "-I", str(FMI_COMMON_SOURCE),
        "-I", str(MODEL_SOURCE),
        f'-DRATTLE_INNER_LIB="{inner_lib_name}"',
        f"-DRATTLE_VR_STATUS_ADDRESS={vr_status_address}u",
        f"-DRATTLE_VR_MESSAGE={vr_message}u",
        *([f"-DRATTLE_VR_LAST_TIME={vr_last_successful_time}u"]
          if vr_last_successful_time is not None else []),
        *([f'-DRATTLE_GUID="{guid}"'] if guid is not None else []),
        *([f'-DRATTLE_MODEL_IDENTIFIER="{model_identifier}"']
          if model_identifier is not None else []),
    ]
    return compile_library(cc, flags, [SHIM_SOURCE, COMMON_SOURCE, FMI2_COMMON_SOURCE,
                                       PORTABLE_SOURCE],
                           Path(out_path),
                           SHIM_SOURCE.name, libs=["-ldl"])


def _model_identifier(fmu: zipfile.ZipFile) -> tuple[str, str | None]:
    """(modelIdentifier, guid) from the FMU's modelDescription."""
    root = ElementTree.fromstring(fmu.read("modelDescription.xml"))
    cosim = root.find("CoSimulation")
    if cosim is None or not cosim.get("modelIdentifier"):
        raise ValueError("modelDescription.xml has no CoSimulation modelIdentifier")
    return cosim.get("modelIdentifier"), root.get("guid")


def install_shim(fmu_path: Path, vr_status_address: int, vr_message: int,
                 vr_last_successful_time: int | None = None, cc: str = "gcc") -> None:
    """Put the status shim into the FMU at ``fmu_path`` (rewritten in place).

    ``binaries/linux64/<modelIdentifier>.so`` (pythonfmu's library) becomes
    ``binaries/linux64/<modelIdentifier>_pythonfmu.so`` and the shim, compiled with ``cc`` for
    the given value references, takes its place.  Every other member is copied byte for byte.
    Only linux64 is handled: other platforms (e.g. ``binaries/win64``) keep pythonfmu's plain
    binary, without the status protocol.  Raises ValueError if the FMU has no linux64 binary
    or already contains the shim.
    """
    fmu_path = Path(fmu_path)
    with zipfile.ZipFile(fmu_path) as src:
        model_identifier, guid = _model_identifier(src)
        binary = f"{_PLATFORM_DIR}/{model_identifier}.so"
        inner = f"{_PLATFORM_DIR}/{model_identifier}{_INNER_SUFFIX}.so"
        names = src.namelist()
        if binary not in names:
            raise ValueError(f"{fmu_path} has no {binary}")
        if inner in names:
            raise ValueError(f"{fmu_path} already contains the shim ({inner} exists)")

        with tempfile.TemporaryDirectory(prefix="rattle_shim_") as tmp:
            shim = compile_shim(Path(tmp) / f"{model_identifier}.so", Path(inner).name,
                                vr_status_address, vr_message, cc=cc, guid=guid,
                                model_identifier=model_identifier,
                                vr_last_successful_time=vr_last_successful_time)
            fd, tmp_fmu = tempfile.mkstemp(suffix=".fmu", dir=fmu_path.parent)
            os.close(fd)
            try:
                with zipfile.ZipFile(tmp_fmu, "w") as dst:
                    for info in src.infolist():
                        data = src.read(info)
                        if info.filename == binary:
                            renamed = zipfile.ZipInfo(inner, date_time=info.date_time)
                            renamed.compress_type = info.compress_type
                            renamed.external_attr = info.external_attr
                            dst.writestr(renamed, data)
                            added = zipfile.ZipInfo(binary, date_time=info.date_time)
                            added.compress_type = zipfile.ZIP_DEFLATED
                            added.external_attr = 0o100755 << 16  # regular file, rwxr-xr-x
                            dst.writestr(added, shim.read_bytes())
                        else:
                            dst.writestr(info, data)
                shutil.copymode(fmu_path, tmp_fmu)  # mkstemp made it 0600
                os.replace(tmp_fmu, fmu_path)
            except BaseException:
                Path(tmp_fmu).unlink(missing_ok=True)
                raise
