"""A corpus of inputs for the model's two readers -- the speed-table reader (a CSV file named by
engine.speed_table, read at exitInitializationMode) and the state-record reader (rm_restore,
behind fmi2SetFMUstate) -- written into a folder, so that both FMU flavours and the library
in process read the same bytes (test_readers.py).

    write_corpus(folder) -> {name: Item}

Tables: line ends (LF, CRLF, CR), a byte-order mark, empty and blank lines, quoting, cells of
512 characters and more, a long first row (header or data), Unicode and full-width digits,
huge, tiny and non-finite numbers, other separators, NUL bytes and bad UTF-8, too few rows,
times that do not increase.  States: records of each unit and phase as the library saves
them, truncated, extended, with edited fields, and large (long tables and strings).  Large
pairs of each kind (``large_*``, one 10 times the other) measure that the readers take time
linear in their input.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

from drive_rattle.library import DRIVELINE, MESH
from drive_rattle.units import Unit

#: The inputs every Driveline of the corpus is initialized with.
DRIVE_INPUTS = {"wheel.phi": 0.0, "wheel.w": 44.57}


@dataclass(frozen=True)
class Item:
    kind: str  # "table" (a CSV file) or "state" (a unit record)
    model: str  # the unit that reads it
    path: Path


def _rows(n: int, start: float = 0.0) -> str:
    return "".join(f"{start + k * 1e-3!r},{80.0 + (k % 13) * 0.5!r}\n" for k in range(n))


TABLES: dict[str, bytes] = {
    "plain": b"time,speed\n0,80\n0.01,95\n0.02,85\n",
    "no header": b"0,80\n0.01,95\n0.02,85\n",
    "crlf": b"time,speed\r\n0,80\r\n0.01,95\r\n0.02,85\r\n",
    "cr only": b"time,speed\r0,80\r0.01,95\r0.02,85\r",
    "no final newline": b"time,speed\n0,80\n0.01,95\n0.02,85",
    "bom header": "\ufefftime,speed\n0,80\n0.01,95\n".encode(),
    "bom data": "\ufeff0,80\n0.01,95\n".encode(),
    "empty lines": b"\n\ntime,speed\n\n0,80\n\n\n0.01,95\n\n",
    "blank lines": b"  \n\t\ntime,speed\n ,  \n0,80\n\"\",\"\"\n0.01,95\n",
    "quoted": b'"time","speed"\n"0","80"\n"0.01","95"\n',
    "quoted spaces": b'" time "," speed "\n" 0 "," 80 "\n" 0.01 "," 95 "\n',
    "space before quote": b'time,speed\n0, "80"\n0.01,95\n',
    "quoted doubled quote header": b'"time ""s""",speed\n0,80\n0.01,95\n',
    "quoted unterminated": b'time,speed\n"0,80\n0.01,95\n',
    "text after quote": b'time,speed\n"0"x,80\n0.01,95\n',
    "quoted decimal comma": b'time,speed\n"0,5",80\n1,95\n',
    "spaces around": b"time , speed\n 0 , 80 \n\t0.01\t,\t95\t\n",
    "extra columns": b"time,speed,torque\n0,80,1\n0.01,95,2,3,4\n",
    "trailing comma": b"time,speed,\n0,80,\n0.01,95,\n",
    "one column": b"time\n0\n0.01\n",
    "semicolons": b"time;speed\n0;80\n0.01;95\n",
    "tabs": b"time\tspeed\n0\t80\n0.01\t95\n",
    "cell 512 time": b"time,speed\n0." + b"0" * 600 + b",80\n0.01,95\n",
    "cell 512 speed": b"time,speed\n0,80." + b"0" * 600 + b"\n0.01,95\n",
    "cell 512 first row data": b"0." + b"0" * 600 + b",80\n0.01,95\n",
    "cell 512 header": b"t" * 600 + b",speed\n0,80\n0.01,95\n",
    "long first row header": b"time [s]," + b"speed [rad/s] " * 400 + b"\n0,80\n0.01,95\n",
    "long first row data": b"0,80" + b",1" * 3000 + b"\n0.01,95\n",
    "cell 512 bad": b"time,speed\n0,8" + b"0" * 600 + b"x\n0.01,95\n",
    "unicode digits": "time,speed\n\u0660,\u0668\u0660\n\u0661,\u0669\u0665\n".encode(),
    "unicode digits first row": "\u0660,\u0668\u0660\n\u0661,\u0669\u0665\n".encode(),
    "fullwidth digits": "time,speed\n\uff10,\uff18\uff10\n\uff11,\uff19\uff15\n".encode(),
    "superscript digit": "time,speed\n0,8\u00b2\n1,95\n".encode(),
    "typo in first row": b"0,8O\n0.01,95\n",
    "plus and dot": b"time,speed\n+0,+80\n.01,95.\n",
    "exponents": b"time,speed\n0e0,8e1\n1E-2,9.5E+1\n",
    "huge speed": b"time,speed\n0,1e308\n1,-1e308\n2,1e308\n",
    "huge speed twice": b"0,1.7e308\n1,1.7e308\n",
    "overflowing time": b"time,speed\n0,80\n1e400,95\n",
    "huge times": b"time,speed\n-1e308,0\n1e308,0\n",
    "time beyond range": b"time,speed\n0,80\n2e10,95\n",
    "angle beyond range": b"time,speed\n0,10000\n200,10000\n",
    "tiny numbers": b"time,speed\n1e-400,80\n1e-300,95\n",
    "negative": b"time,speed\n-5,-80\n-4,-95\n",
    "inf": b"time,speed\n0,inf\n1,95\n",
    "infinity word": b"time,speed\n0,80\nInfinity,95\n",
    "nan": b"time,speed\n0,nan\n1,95\n",
    "hex": b"time,speed\n0x0,80\n0x1,95\n",
    "underscore": b"time,speed\n0,8_0\n1,95\n",
    "not increasing": b"time,speed\n0,80\n0,95\n",
    "decreasing": b"time,speed\n1,80\n0,95\n",
    "header only": b"time,speed\n",
    "one row": b"time,speed\n0,80\n",
    "empty": b"",
    "only blank": b"\n\n  \n",
    "nul byte": b"time,speed\n0,80\n0.01,9\x005\n",
    "bad utf-8": b"time,speed\n0,80\n0.01,95\xff\n",
    "utf-16": "time,speed\n0,80\n0.01,95\n".encode("utf-16"),
    "many rows": ("time,speed\n" + _rows(20_000)).encode(),
}


def _table_file(folder: Path, name: str, data: bytes) -> Path:
    path = folder / (name.replace(" ", "_") + ".csv")
    path.write_bytes(data)
    return path


def _record(kind: int, parameters=None, steps: int = 0, initialize: bool = True,
            terminate: bool = False) -> bytes:
    unit = Unit(kind, parameters, DRIVE_INPUTS if kind == DRIVELINE else None,
                initialize=initialize)
    for _ in range(steps):
        unit.advance(1e-4)
    if terminate:
        unit.terminate()
    record = unit.save()
    unit.close()
    return record


def _with_time(record: bytes, start: float, time: float) -> bytes:
    """The record with its header's start time and time replaced (offsets 24 and 32)."""
    return record[:24] + struct.pack("<dd", start, time) + record[40:]


def write_corpus(folder: Path) -> dict[str, Item]:
    folder = Path(folder)
    tables, states = folder / "tables", folder / "states"
    tables.mkdir(parents=True, exist_ok=True)
    states.mkdir(parents=True, exist_ok=True)
    items: dict[str, Item] = {}
    for name, data in TABLES.items():
        items[f"table {name}"] = Item("table", "Driveline", _table_file(tables, name, data))
    # large tables: many rows, and one long cell, at 1x and 10x (within the 4 MiB limit)
    for scale, label in ((1, "1x"), (10, "10x")):
        items[f"table large_rows {label}"] = Item("table", "Driveline", _table_file(
            tables, f"large_rows_{label}", ("time,speed\n" + _rows(20_000 * scale)).encode()))
        items[f"table large_cell {label}"] = Item("table", "Driveline", _table_file(
            tables, f"large_cell_{label}",
            b"time,speed\n0." + b"0" * (300_000 * scale) + b"1,80\n0.01,95\n"))
    # states
    table = items["table plain"].path
    records = {
        "mesh instantiated": (MESH, _record(MESH, initialize=False)),
        "mesh stepping": (MESH, _record(MESH, steps=3)),
        "mesh terminated": (MESH, _record(MESH, steps=1, terminate=True)),
        "driveline stepping": (DRIVELINE, _record(DRIVELINE, steps=3)),
        "driveline with table": (DRIVELINE, _record(DRIVELINE, {"engine.speed_table":
                                                                str(table)}, steps=2)),
    }
    variants: dict[str, tuple[int, bytes]] = dict(records)
    for name, (kind, record) in records.items():
        for cut in (0, 7, 8, 43, 44, 60, len(record) // 2, len(record) - 1):
            variants[f"{name} cut at {cut}"] = (kind, record[:cut])
        variants[f"{name} extended"] = (kind, record + b"\0" * 8)
        newer = int.from_bytes(record[8:12], "little") + 1  # a version this build cannot read
        variants[f"{name} newer version"] = (kind, record[:8] + newer.to_bytes(4, "little")
                                             + record[12:])
        variants[f"{name} start 1e308"] = (kind, _with_time(record, 1e308, 0.0))
        variants[f"{name} time nan"] = (kind, _with_time(record, 0.0, float("nan")))
    variants["mesh record as driveline"] = (DRIVELINE, records["mesh stepping"][1])
    variants["garbage"] = (MESH, bytes(range(256)) * 4)
    # large: a saved table of many rows, a long string, trailing bytes; 1x and 10x
    for scale, label in ((1, "1x"), (10, "10x")):
        rows = _table_file(tables, f"state_rows_{label}",
                           ("time,speed\n" + _rows(20_000 * scale)).encode())
        variants[f"large_table_state {label}"] = (DRIVELINE, _record(
            DRIVELINE, {"engine.speed_table": str(rows)}, steps=1))
        variants[f"large_string_state {label}"] = (DRIVELINE, _record(
            DRIVELINE, {"engine.speed_table": "x" * (300_000 * scale)}, initialize=False))
        variants[f"large_trailing_state {label}"] = (MESH, records["mesh stepping"][1]
                                                     + bytes(300_000 * scale))
    for name, (kind, record) in variants.items():
        path = states / (name.replace(" ", "_") + ".bin")
        path.write_bytes(record)
        items[f"state {name}"] = Item("state", "GearMeshRattle" if kind == MESH
                                      else "Driveline", path)
    return items
