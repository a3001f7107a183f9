"""The model library's unit record (``rm_save``: the payload of a serialized FMU state), read
and written field by field, so that the adversarial tests can forge states that pass the
envelope and reach the library's checks (``rm_restore``).  Written from the record's
description (rattle_model.h, unit.c, unit_mesh.c), independently of the library's code.

Little-endian:  "RATLUNIT", u32 version, u32 kind, u32 phase, u32 motion_set, f64 start_time,
f64 time, u32 n_variables, then every parameter and input in value-reference order (Real:
f64; Integer, Boolean: i64; String: u32 length + bytes), u32 has_model, then the model's own
fields (``MESH_MODEL`` for GearMeshRattle; opaque bytes otherwise).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

MAGIC = b"RATLUNIT"
HEADER = struct.Struct("<8sIIIIddI")
#: The GearMeshRattle model's fields: (name, format) in record order.
MESH_MODEL = (("wheel.phi", "d"), ("wheel.w", "d"), ("flank", "q"), ("v_drive", "d"),
              ("v_coast", "d"), ("v_last", "d"), ("n_drive", "q"), ("n_coast", "q"),
              ("rattle_index", "d"), ("tau_wheel_mean", "d"), ("tau_pinion_mean", "d"),
              ("W_peak", "d"), ("delta_peak", "d"), ("onsets_drive", "q"),
              ("onsets_coast", "q"), ("pinion_phi", "d"), ("pinion_w", "d"))


@dataclass
class Record:
    """A unit record, its fields editable (``encode`` writes it back)."""

    version: int
    kind: int
    phase: int
    motion_set: int
    start_time: float
    time: float
    n_variables: int
    values: dict = field(default_factory=dict)  # public name -> value (str for Strings)
    has_model: int = 0
    model: dict = field(default_factory=dict)  # MESH_MODEL fields (GearMeshRattle)
    rest: bytes = b""  # the model's other bytes
    _types: list = field(default_factory=list, repr=False)  # (name, FMI type) in order

    @classmethod
    def decode(cls, data: bytes, variables: dict) -> Record:
        """The record ``data`` of a unit whose modelDescription ``variables`` are
        name -> (vr, FMI type, causality) (``raw_fmi.Model.variables``)."""
        magic, version, kind, phase, motion, t0, t, n = HEADER.unpack_from(data, 0)
        if magic != MAGIC:
            raise ValueError("not a unit record")
        pos = HEADER.size
        types = [(name, kind_) for name, (_, kind_, causality) in
                 sorted(variables.items(), key=lambda item: item[1][0])
                 if causality != "output"]
        values = {}
        for name, fmi_type in types:
            if fmi_type == "Real":
                (values[name],), pos = struct.unpack_from("<d", data, pos), pos + 8
            elif fmi_type == "String":
                (length,) = struct.unpack_from("<I", data, pos)
                values[name] = data[pos + 4:pos + 4 + length].decode("utf-8", "replace")
                pos += 4 + length
            else:
                (values[name],), pos = struct.unpack_from("<q", data, pos), pos + 8
        (has_model,), pos = struct.unpack_from("<I", data, pos), pos + 4
        model = {}
        if has_model and kind == 0:
            for name, fmt in MESH_MODEL:
                (model[name],), pos = struct.unpack_from("<" + fmt, data, pos), pos + 8
        return cls(version, kind, phase, motion, t0, t, n, values, has_model, model, data[pos:],
                   types)

    def encode(self) -> bytes:
        out = [HEADER.pack(MAGIC, self.version, self.kind, self.phase, self.motion_set,
                           self.start_time, self.time, self.n_variables)]
        for name, fmi_type in self._types:
            if name not in self.values:
                continue  # a missing variable: the record ends early
            value = self.values[name]
            if fmi_type == "Real":
                out.append(struct.pack("<d", value))
            elif fmi_type == "String":
                raw = value if isinstance(value, bytes) else value.encode()
                out.append(struct.pack("<I", len(raw)) + raw)
            else:
                out.append(struct.pack("<q", value))
        out.append(struct.pack("<I", self.has_model))
        if self.model:
            out.extend(struct.pack("<" + fmt, self.model[name]) for name, fmt in MESH_MODEL)
        out.append(self.rest)
        return b"".join(out)
