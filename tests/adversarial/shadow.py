"""The model library in this process, driven call for call as an FMU instance is: the expected
statuses, values and states of the FMI faces (both flavours hold no model of their own, so an
FMU must answer exactly what the library answers to the same calls).

The library is loaded by path (``drive_rattle.library.load``): by default the one the source
checkout builds in place, which is not the copy inside an FMU -- so a variant of an FMU (a
sanitizer build, a mutant) is held against the library as its sources have it.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

from drive_rattle import library

TYPES = ("Real", "Integer", "Boolean", "String")
_CTYPES = {"Real": ctypes.c_double, "Integer": ctypes.c_int32, "Boolean": ctypes.c_int32,
           "String": ctypes.c_char_p}
KINDS = {"GearMeshRattle": library.MESH, "Driveline": library.DRIVELINE}


def _uints(values) -> ctypes.Array:
    values = list(values)
    return (ctypes.c_uint * max(1, len(values)))(*values)


class Shadow:
    """One library unit of the model ``identifier`` (an FMU's model identifier), made with the
    FMU's resources folder (where relative speed-table paths resolve)."""

    def __init__(self, identifier: str, resources: Path | bytes | None,
                 path: str | Path | None = None):
        self.lib = library.load(path)
        if isinstance(resources, Path):
            resources = bytes(resources)
        unit = self.lib.rm_new(KINDS[identifier], resources)
        assert unit, "rm_new failed"
        self.unit = ctypes.c_void_p(unit)  # a raw pointer: LeakSanitizer sees it

    def free(self) -> None:
        if self.unit:
            self.lib.rm_free(self.unit)
            self.unit = None

    def message(self) -> str:
        return library.message(self.lib, self.unit)

    # -- the calls, as the FMI calls name them; each returns the library's status
    def set(self, kind: str, vrs, values) -> int:
        values = [v.encode() if isinstance(v, str) else v for v in values]
        array = (_CTYPES[kind] * max(1, len(values)))(*values)
        return getattr(self.lib, f"rm_set_{kind.lower()}")(self.unit, _uints(vrs), len(vrs),
                                                            array)

    def get(self, kind: str, vrs) -> tuple[int, list]:
        out = (_CTYPES[kind] * max(1, len(vrs)))()
        status = getattr(self.lib, f"rm_get_{kind.lower()}")(self.unit, _uints(vrs), len(vrs),
                                                              out)
        values = list(out)[:len(vrs)]
        if kind == "String":
            values = [v.decode("utf-8", "replace") if v is not None else "" for v in values]
        return status, values

    def setup(self, start: float) -> int:
        return self.lib.rm_setup(self.unit, start)

    def enter(self) -> int:
        return self.lib.rm_enter_initialization(self.unit)

    def exit(self) -> int:
        return self.lib.rm_exit_initialization(self.unit)

    def terminate(self) -> int:
        return self.lib.rm_terminate(self.unit)

    def reset(self) -> int:
        return self.lib.rm_reset(self.unit)

    def step(self, t: float, h: float) -> int:
        return self.lib.rm_do_step(self.unit, t, h)

    def save(self) -> bytes:
        size = ctypes.c_size_t()
        assert self.lib.rm_save(self.unit, None, 0, ctypes.byref(size)) == library.OK
        buf = ctypes.create_string_buffer(max(1, size.value))
        assert self.lib.rm_save(self.unit, buf, size.value, ctypes.byref(size)) == library.OK
        return buf.raw[:size.value]

    def restore(self, record: bytes) -> int:
        return self.lib.rm_restore(self.unit, record, len(record))
