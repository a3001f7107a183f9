"""The model library through ctypes: the one implementation of the model
(``fmu_src/rattle_model``, C, ``rattle_model.h``), loaded from a shared library.

Where the library is looked for, in order:

* ``$RATTLE_MODEL_LIBRARY``, a path to it;
* next to this package (``rattle_model.so`` on Linux, ``rattle_model.dll`` on Windows): where
  a pythonfmu FMU ships it, and where ``drive-rattle-build`` (every build, or
  ``drive-rattle-build --library``) writes it, in a source checkout and in an installed wheel.

Where it is missing there and the project is installed with its build (an installed wheel or
a checkout; not inside an FMU), the first load builds it from the sources, through the
``drive_rattle.library`` entry point that the build declares (so that this runtime package
imports nothing but the standard library).

In a source checkout the library records the hash of the sources it was built from
(``rm_build_id``); a library older than its sources is refused with the command that rebuilds
it, so that nothing runs on a stale model.

Standard library only (it ships in the pythonfmu FMUs).  The calls are thin: statuses come back
as :class:`ModelError` (a ValueError) carrying the library's own message.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import sys
import threading
from pathlib import Path

#: The unit kinds (RmKind).
MESH, DRIVELINE = 0, 1
#: Statuses (RmStatus: fmi2Status's numbers).
OK, WARNING, ERROR = 0, 1, 3
#: Phases (RmPhase).
PHASES = ("instantiated", "initialization", "stepping", "terminated")
#: Types and causalities of the variable tables.
TYPES = ("Real", "Integer", "Boolean", "String")
CAUSALITIES = ("parameter", "input", "output")
#: Event kinds (RM_EVENT_...).
EVENT_KINDS = ("onset", "release", "reversal", "pair", "touch")
#: Largest number of events of a step the library keeps (RM_MAX_EVENTS).
MAX_EVENTS = 512
#: The interface version this binding speaks (RM_API_VERSION).
API_VERSION = 1

LIBRARY_NAME = "rattle_model.dll" if sys.platform == "win32" else (
    "rattle_model.dylib" if sys.platform == "darwin" else "rattle_model.so")
#: Where the C sources of the library are: a source checkout (``fmu_src/rattle_model``), or
#: an installed wheel (package data of the build); neither exists inside an FMU.
_SOURCE_FOLDERS = (Path(__file__).resolve().parent.parent / "rattle_model",
                   Path(__file__).resolve().parent.parent / "drive_rattle_build" / "sources"
                   / "rattle_model")
SOURCES = next((p for p in _SOURCE_FOLDERS if p.is_dir()), _SOURCE_FOLDERS[0])
#: The entry-point group of the builder of a missing library (drive_rattle_build.library).
BUILDER_GROUP = "drive_rattle.library"


class ModelError(ValueError):
    """A call the model library refused; the message is the library's."""


class LibraryError(RuntimeError):
    """The model library cannot be loaded (missing, stale or of another version)."""


class RmVariable(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char_p), ("type", ctypes.c_int), ("causality", ctypes.c_int),
                ("unit", ctypes.c_char_p), ("start", ctypes.c_double),
                ("start_string", ctypes.c_char_p), ("has_min", ctypes.c_int),
                ("has_max", ctypes.c_int), ("min_exclusive", ctypes.c_int),
                ("max_exclusive", ctypes.c_int), ("min", ctypes.c_double),
                ("max", ctypes.c_double), ("n_choices", ctypes.c_int),
                ("choices", ctypes.POINTER(ctypes.c_int)), ("allowed", ctypes.c_char_p)]


class RmEvent(ctypes.Structure):
    _fields_ = [("time", ctypes.c_double), ("kind", ctypes.c_int), ("flank", ctypes.c_int),
                ("speed", ctypes.c_double)]


class RmStepReport(ctypes.Structure):
    _fields_ = [("count", ctypes.c_size_t), ("total", ctypes.c_size_t),
                ("events", ctypes.POINTER(RmEvent)), ("rhs_evaluations", ctypes.c_int64),
                ("contact_substeps", ctypes.c_int64)]


def source_id(folder: Path = SOURCES) -> str:
    """The hash of the library's sources (every .c and .h in ``folder``, by name and content):
    what the build compiles into ``rm_build_id``."""
    digest = hashlib.sha256()
    for path in sorted(Path(folder).glob("*.[ch]")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def default_path() -> Path:
    """Where the library is looked for: ``$RATTLE_MODEL_LIBRARY``, else next to this package."""
    env = os.environ.get("RATTLE_MODEL_LIBRARY")
    return Path(env) if env else Path(__file__).resolve().parent / LIBRARY_NAME


_P = ctypes.c_void_p
_U = ctypes.POINTER(ctypes.c_uint)
_D = ctypes.POINTER(ctypes.c_double)
_I32 = ctypes.POINTER(ctypes.c_int32)
_SIGNATURES = {
    "rm_api_version": ([], ctypes.c_int),
    "rm_build_id": ([], ctypes.c_char_p),
    "rm_variables": ([ctypes.c_int], ctypes.POINTER(RmVariable)),
    "rm_variable_count": ([ctypes.c_int], ctypes.c_size_t),
    "rm_new": ([ctypes.c_int, ctypes.c_char_p], _P),
    "rm_free": ([_P], None),
    "rm_kind": ([_P], ctypes.c_int),
    "rm_phase": ([_P], ctypes.c_int),
    "rm_message": ([_P], ctypes.c_char_p),
    "rm_setup": ([_P, ctypes.c_double], ctypes.c_int),
    "rm_enter_initialization": ([_P], ctypes.c_int),
    "rm_exit_initialization": ([_P], ctypes.c_int),
    "rm_do_step": ([_P, ctypes.c_double, ctypes.c_double], ctypes.c_int),
    "rm_terminate": ([_P], ctypes.c_int),
    "rm_reset": ([_P], ctypes.c_int),
    "rm_last_successful_time": ([_P, _D], ctypes.c_int),
    "rm_time": ([_P], ctypes.c_double),
    "rm_set_real": ([_P, _U, ctypes.c_size_t, _D], ctypes.c_int),
    "rm_set_integer": ([_P, _U, ctypes.c_size_t, _I32], ctypes.c_int),
    "rm_set_boolean": ([_P, _U, ctypes.c_size_t, _I32], ctypes.c_int),
    "rm_set_string": ([_P, _U, ctypes.c_size_t, ctypes.POINTER(ctypes.c_char_p)], ctypes.c_int),
    "rm_get_real": ([_P, _U, ctypes.c_size_t, _D], ctypes.c_int),
    "rm_get_integer": ([_P, _U, ctypes.c_size_t, _I32], ctypes.c_int),
    "rm_get_boolean": ([_P, _U, ctypes.c_size_t, _I32], ctypes.c_int),
    "rm_get_string": ([_P, _U, ctypes.c_size_t, ctypes.POINTER(ctypes.c_char_p)], ctypes.c_int),
    "rm_save": ([_P, ctypes.c_void_p, ctypes.c_size_t, ctypes.POINTER(ctypes.c_size_t)],
                ctypes.c_int),
    "rm_restore": ([_P, ctypes.c_char_p, ctypes.c_size_t], ctypes.c_int),
    "rm_step_report": ([_P, ctypes.POINTER(RmStepReport)], ctypes.c_int),
    "rm_check_parameters": ([_P], ctypes.c_int),
    "rm_coupled_start": ([_P, _P, ctypes.c_double, _D, _D], ctypes.c_int),
    "rm_run_coupled": ([_P, _P, ctypes.c_int64, ctypes.c_int64, ctypes.c_int64, _U,
                        ctypes.POINTER(ctypes.c_int), ctypes.c_size_t, _D, _D, ctypes.c_size_t,
                        ctypes.POINTER(ctypes.c_size_t)], ctypes.c_int),
    "rm_describe": ([_P, ctypes.POINTER(ctypes.c_char_p), _D, ctypes.c_size_t,
                     ctypes.POINTER(ctypes.c_size_t)], ctypes.c_int),
}

#: The test-only probes (rm_probe.h): in the library built in place (what the Python API and
#: the tests load), in no shipped FMU's library; bound where the library has them.
_PROBES = {
    "rm_probe_contact_law": ([_P, ctypes.c_double, _D], ctypes.c_int),
    "rm_probe_exact_ellipse": ([_P, ctypes.c_double, _D], ctypes.c_int),
    "rm_probe_restitution": ([_P, ctypes.c_double, _D], ctypes.c_int),
    "rm_probe_damping_factor": ([_P, ctypes.c_double, ctypes.c_double, _D], ctypes.c_int),
    "rm_probe_pairs": ([_P, ctypes.c_int, ctypes.c_double, _D, ctypes.c_size_t,
                        ctypes.POINTER(ctypes.c_size_t)], ctypes.c_int),
    "rm_probe_loads": ([_P, ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_double,
                        ctypes.c_double, ctypes.c_double, _D, _D, ctypes.c_size_t,
                        ctypes.POINTER(ctypes.c_size_t)], ctypes.c_int),
    "rm_probe_pair_laws": ([_P, ctypes.c_int, ctypes.c_double, _D, ctypes.c_size_t,
                            ctypes.POINTER(ctypes.c_size_t)], ctypes.c_int),
    "rm_probe_approach": ([_P, ctypes.c_double, ctypes.c_double, ctypes.c_double,
                           ctypes.c_double, ctypes.c_double, _D], ctypes.c_int),
    "rm_probe_squeeze": ([_P, ctypes.c_int, ctypes.c_double, ctypes.c_double, _D],
                         ctypes.c_int),
}

_LOADED: dict[str, ctypes.CDLL] = {}
_LOCK = threading.Lock()


def load(path: str | Path | None = None) -> ctypes.CDLL:
    """The model library at ``path`` (default :func:`default_path`), loaded once per path.
    :class:`LibraryError` saying what to do when it is missing, stale or of another version."""
    p = Path(path) if path is not None else default_path()
    key = str(p)
    lib = _LOADED.get(key)
    if lib is not None:
        return lib
    with _LOCK:
        lib = _LOADED.get(key)
        if lib is not None:
            return lib
        rebuild = ("build it from the sources with `drive-rattle-build --library` (or "
                   "`python build_fmu.py --library` in a clone)")
        if not p.is_file() and path is None and "RATTLE_MODEL_LIBRARY" not in os.environ:
            _build_missing(p)
        if not p.is_file():
            raise LibraryError(f"the model library {p} is missing: {rebuild}")
        try:
            lib = ctypes.CDLL(str(p.resolve()))
            for name, (args, res) in _SIGNATURES.items():
                fn = getattr(lib, name)
                fn.argtypes, fn.restype = args, res
            for name, (args, res) in _PROBES.items():
                try:
                    fn = getattr(lib, name)
                except (AttributeError, ValueError):  # absent (ValueError: ctypes decoding
                    continue                          # the dlerror of a non-UTF-8 path)
                fn.argtypes, fn.restype = args, res
        except (OSError, AttributeError) as err:
            raise LibraryError(f"the model library {p} cannot be loaded ({err}): {rebuild}"
                               ) from None
        if lib.rm_api_version() != API_VERSION:
            raise LibraryError(f"the model library {p} speaks interface version "
                               f"{lib.rm_api_version()}, this binding {API_VERSION}: {rebuild}")
        if path is None and "RATTLE_MODEL_LIBRARY" not in os.environ and SOURCES.is_dir():
            built, current = lib.rm_build_id().decode(), source_id()
            if built != current:
                raise LibraryError(f"the model library {p} was built from other sources "
                                   f"({built}) than those in {SOURCES} ({current}): {rebuild}")
        _LOADED[key] = lib
        return lib


def _build_missing(path: Path) -> None:
    """Build the missing default library with the builder the installed build declares (the
    ``drive_rattle.library`` entry point), saying so on stderr; nothing where there is none
    (inside an FMU).  A failed build raises LibraryError with the builder's message."""
    from importlib.metadata import entry_points

    builders = list(entry_points(group=BUILDER_GROUP))
    if not builders or not SOURCES.is_dir():
        return
    print(f"drive-rattle: building the model library {path} from its sources (once)",
          file=sys.stderr, flush=True)
    try:
        builders[0].load()()
    except Exception as err:  # the builder's own error (no compiler, a failed compile)
        raise LibraryError(f"the model library {path} is missing and could not be built: "
                           f"{err}") from None


def message(lib: ctypes.CDLL, unit) -> str:
    """The library's message of the unit's last call."""
    return lib.rm_message(unit).decode("utf-8", "replace")


def variables(kind: int, lib: ctypes.CDLL | None = None) -> list[dict]:
    """The variables of a unit kind in value-reference order, as the library's tables hold
    them (generated from the specs): name, type, causality, unit, start, limits, allowed."""
    lib = lib or load()
    table = lib.rm_variables(kind)
    out = []
    for vr in range(lib.rm_variable_count(kind)):
        v = table[vr]
        out.append({
            "vr": vr, "name": v.name.decode(), "type": TYPES[v.type],
            "causality": CAUSALITIES[v.causality], "unit": v.unit.decode(),
            "start": v.start_string.decode() if v.type == 3 else v.start,
            "min": v.min if v.has_min else None, "max": v.max if v.has_max else None,
            "choices": [v.choices[k] for k in range(v.n_choices)],
            "allowed": v.allowed.decode()})
    return out
