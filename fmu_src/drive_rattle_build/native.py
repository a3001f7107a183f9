"""Native FMUs: GearMeshRattle and Driveline implemented entirely in C, with no Python at run
time, built for linux64 and win64 and shipped with their C sources.

The C code (``fmu_src/native``: ``fmi2_native.c`` the FMI glue written once for both units,
``rattle_model.c`` the units, ``rattle_pytext.c`` Python-compatible text and JSON,
``rattle_files.c`` the file system, ``rattle_kernel.c`` the stepper kernel the pythonfmu FMUs
load too) behaves as the pythonfmu FMUs do -- the same variables, checks, statuses, messages
and FMU-state format -- and on linux64 gives their outputs bit for bit.  What the C needs from
the Python specs is rendered here, never copied by hand:

* ``rattle_native_tables.h`` / ``.c``: the unit, its GUID and model identifier, every public
  variable in value-reference order (name, FMI type, causality, unit, start value, limits,
  allowed enumeration codes, the "allowed" text of its messages), a ``RN_VR_<NAME>`` macro per
  variable, and the constants of the Python modules the C transcribes;
* ``modelDescription.xml``: the pythonfmu FMU's (``model_description.model_description``,
  from the same slave class), with its own GUID, ``needsExecutionTool="false"`` and the
  ``<SourceFiles>``; the interface is checked against ``modelDescription_templates/``.

``build_native(out_dir)`` compiles, packs and validates both FMUs into ``out_dir``
(``dist/native`` from ``drive-rattle-build`` / ``python build_fmu.py``).  Build time only: it
needs pythonfmu (for the slave classes), fmpy (the FMI 2.0 headers and validate_fmu), a C
compiler for linux64 and the ``ziglang`` package for win64.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import uuid
import zipfile
from collections.abc import Sequence
from pathlib import Path
from xml.etree import ElementTree
from xml.etree.ElementTree import Element, SubElement

from drive_rattle import driveline, geometry, hertz, lubrication, mesh, roots, stepper
from drive_rattle.interface import MODELS
from drive_rattle.kernel_layout import c_name
from drive_rattle_fmi import slave as slave_module
from drive_rattle_fmi.model_description import model_description

from . import kernel, templates
from .compiler import BuildError, c_compiler
from .documentation import html_page
from .fmu import slave_class, validate
from .paths import DIST
from .paths import NATIVE as NATIVE_DIR
from .shim import fmi2_headers

#: Compiled, in this order; every one is listed in <SourceFiles>.
C_SOURCES = ("fmi2_native.c", "rattle_fmi_common.c", "rattle_model.c", "rattle_pytext.c",
             "rattle_files.c", "rattle_kernel.c", "rattle_native_tables.c")
HEADERS = ("rattle_native.h", "rattle_fmi_common.h", "rattle_kernel_layout.h",
           "rattle_native_tables.h")
#: The FMI 2.0 headers, as the standard ships them (fmpy bundles them).
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
GENERATED = ("rattle_native_tables.h", "rattle_native_tables.c")
#: IEEE arithmetic without contraction, as the bit-for-bit identity with the Python core needs
#: (docs/kernel.md); warnings on.
CFLAGS = ("-std=c99", "-O2", "-fno-fast-math", "-ffp-contract=off", "-Wall", "-Wextra")
#: platform folder -> (binary suffix, ziglang target or None for the build machine's compiler)
PLATFORMS = {"linux64": (".so", None), "win64": (".dll", "x86_64-windows-gnu")}
#: The file in resources/ that identifies the FMU (the native counterpart of pythonfmu's
#: slavemodule.txt): its model identifier on the first line.
RESOURCE_MARKER = "model_identifier.txt"
UNITS = {"GearMeshRattle": "RN_UNIT_MESH", "Driveline": "RN_UNIT_DRIVELINE"}
GENERATION_TOOL = "drive-rattle-build (native C)"
#: Where the native FMUs go, below the output folder.
NATIVE_SUBDIR = "native"

#: Output groups: when an output is read after a step, only its group is computed ("compute
#: what is read"): the wheel's angle and speed, the outputs that are copies of the state and
#: the last step, and the rest, which need the mesh loads (rattle_kernel.c's rk_outputs).
GROUP_QUICK, GROUP_STATE, GROUP_LOADS = 1, 2, 4
MESH_QUICK = ("wheel.phi", "wheel.w")
MESH_STATE = ("wheel.tau_mesh", "pinion.tau_mesh", "mesh.W_peak", "mesh.delta_peak",
              "mesh.v_impact", "mesh.impacts_drive", "mesh.impacts_coast",
              "mesh.transmission_error", "mesh.impact_energy", "mesh.rattle_index")

#: Constants of the Python modules the C code reads: (C name, value).
CONSTANTS = (
    ("RN_MAX_PAIR_SLOTS", geometry.MAX_PAIR_SLOTS),
    ("RN_BREAKPOINT_TOLERANCE", geometry.BREAKPOINT_TOLERANCE),
    ("RN_MAX_CHEBYSHEV_TERMS", hertz.MAX_CHEBYSHEV_TERMS),
    ("RN_CHEBYSHEV_TOLERANCE", hertz.CHEBYSHEV_TOLERANCE),
    ("RN_CIRCLE_RATIO", hertz.CIRCLE_RATIO),
    ("RN_AGM_TOLERANCE", hertz.AGM_TOLERANCE),
    ("RN_AGM_MAX_ITERATIONS", hertz.AGM_MAX_ITERATIONS),
    ("RN_LAW_EXACT", hertz.LAW_EXACT),
    ("RN_LAW_EQUIVALENT_SPHERE", hertz.LAW_EQUIVALENT_SPHERE),
    ("RN_ROOTS_MAX_ITERATIONS", roots.MAX_ITERATIONS),
    ("RN_BRENT_RTOL", roots.BRENT_RTOL),
    ("RN_DISSIPATION_NONE", mesh.DISSIPATION_NONE),
    ("RN_DISSIPATION_RESTITUTION", mesh.DISSIPATION_RESTITUTION),
    ("RN_DISSIPATION_FACTOR", mesh.DISSIPATION_FACTOR),
    ("RN_MAX_INITIAL_PENETRATION", stepper.MAX_INITIAL_PENETRATION),
    ("RN_MAX_PENETRATION_MODULES", stepper.MAX_PENETRATION_MODULES),
    ("RN_GRAZING_SAMPLES", stepper.GRAZING_SAMPLES),
    ("RN_CONTACT_RATE_SAFETY", stepper.CONTACT_RATE_SAFETY),
    ("RN_MAX_CONTACT_SUBSTEPS", stepper.MAX_CONTACT_SUBSTEPS),
    ("RN_EVENT_XTOL", stepper.EVENT_XTOL),
    ("RN_EVENT_RTOL", stepper.EVENT_RTOL),
    ("RN_EQUILIBRIUM_XTOL", stepper.EQUILIBRIUM_XTOL),
    ("RN_HERTZ_ROOT_XTOL", hertz.ROOT_XTOL),
    ("RN_RESTITUTION_XTOL", hertz.RESTITUTION_XTOL),
    ("RN_ENGAGEMENT_MIN_FRACTION", stepper.ENGAGEMENT_MIN_FRACTION),
    ("RN_GRID_SLACK", stepper.GRID_SLACK),
    ("RN_LAMBDA_BOUNDARY", lubrication.LAMBDA_BOUNDARY),
    ("RN_LAMBDA_FULL_FILM", lubrication.LAMBDA_FULL_FILM),
    ("RN_N_ORDERS", driveline.N_ORDERS),
    ("RN_MAX_SPEED_TABLE_BYTES", driveline.MAX_SPEED_TABLE_BYTES),
    ("RN_MAX_PATH_BYTES", driveline.MAX_PATH_BYTES),
    ("RN_RK4_MAX_STEP_SCALE", driveline.RK4_MAX_STEP_SCALE),
    ("RN_COMMUNICATION_POINT_TOLERANCE", slave_module.COMMUNICATION_POINT_TOLERANCE),
    ("RN_STATE_FORMAT", slave_module.STATE_FORMAT),
    ("RN_MAX_STATE_INTEGER", slave_module.MAX_STATE_INTEGER),
)


def _c_number(value) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int):
        return f"{value}LL" if abs(value) > 2**31 - 1 else str(value)
    text = repr(float(value))
    if text in ("inf", "-inf", "nan"):
        raise ValueError(f"constant {value!r} has no C literal")
    return text


def _c_string(text: str) -> str:
    """A C string literal of UTF-8 text (every byte beyond ASCII as an octal escape)."""
    out = []
    for byte in text.encode("utf-8"):
        ch = chr(byte)
        if ch in '"\\':
            out.append("\\" + ch)
        elif 32 <= byte < 127 and ch != "?":  # no trigraphs
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def _variables(slave) -> list[dict]:
    """The public variables of a slave instance in value-reference order, with their specs."""
    cls = type(slave)
    inputs = {s.name: s for s in cls.INPUTS}
    outputs = {s.name: s for s in cls.OUTPUTS}
    out = []
    for vr, var in enumerate(slave.public_variables):
        if var.value_reference != vr:
            raise RuntimeError(f"{var.name}: value reference {var.value_reference} != {vr}")
        name = var.name
        fmi_type = slave._fmi_types[name]
        entry = {"name": name, "vr": vr, "fmi_type": fmi_type, "unit": "", "start": None,
                 "min": None, "max": None, "min_exclusive": False, "max_exclusive": False,
                 "choices": (), "allowed": "", "group": 0}
        if name in slave._param_specs:
            spec = slave._param_specs[name]
            entry.update(causality="parameter", unit=spec.unit, start=spec.default,
                         min=spec.minimum, max=spec.maximum, min_exclusive=spec.min_exclusive,
                         max_exclusive=spec.max_exclusive,
                         choices=tuple(spec.choices or ()), allowed=spec.allowed())
        elif name in inputs:
            spec = inputs[name]
            entry.update(causality="input", unit=spec.unit, start=spec.start, min=spec.minimum,
                         max=spec.maximum,
                         allowed=f"[{spec.minimum:g}, {spec.maximum:g}] {spec.unit}")
        else:
            spec = outputs[name]
            if cls.__name__ == "GearMeshRattle":
                group = (GROUP_QUICK if name in MESH_QUICK else
                         GROUP_STATE if name in MESH_STATE else GROUP_LOADS)
            else:
                group = GROUP_STATE
            entry.update(causality="output", unit=spec.unit,
                         start=0.0 if fmi_type == "Real" else 0, group=group)
        out.append(entry)
    return out


def render_tables(slave, guid: str) -> tuple[str, str]:
    """The texts of ``rattle_native_tables.h`` and ``rattle_native_tables.c`` for a slave
    instance and the FMU's GUID."""
    cls = type(slave)
    name = cls.__name__
    variables = _variables(slave)
    n_params = sum(v["causality"] == "parameter" for v in variables)
    if any(v["causality"] == "parameter" for v in variables[n_params:]):
        raise RuntimeError(f"{name}: the parameters must come first in value-reference order")
    macros = {}
    for v in variables:
        macro = f"RN_VR_{c_name(v['name'])}"
        if macro in macros:
            raise RuntimeError(f"{v['name']} and {macros[macro]} both give the C name {macro}")
        macros[macro] = v["name"]
    outputs = [v["vr"] for v in variables if v["causality"] == "output"]
    by_name = sorted(variables, key=lambda v: v["name"])  # Python's str order (code points)
    h = [f"/* GENERATED by drive_rattle_build/native.py for {name} -- do not edit. */",
         "#ifndef RATTLE_NATIVE_TABLES_H", "#define RATTLE_NATIVE_TABLES_H", "",
         f"#define {UNITS[name]} 1",
         f"#define RN_MODEL_IDENTIFIER {_c_string(name)}",
         f"#define RN_GUID {_c_string(guid)}",
         f"#define RN_N_VARIABLES {len(variables)}",
         f"#define RN_N_PARAMETERS {n_params}",
         f"#define RN_N_OUTPUTS {len(outputs)}",
         f"#define RN_DEFAULT_STEP_SIZE {_c_number(cls.DEFAULT_EXPERIMENT['stepSize'])}",
         f"#define RN_GROUP_QUICK {GROUP_QUICK}u",
         f"#define RN_GROUP_STATE {GROUP_STATE}u",
         f"#define RN_GROUP_LOADS {GROUP_LOADS}u",
         "#define RN_MODE_NAME_LIST {"
         + ", ".join(_c_string(m) for m in slave_module.MODES) + "}",
         "", "/* value references */"]
    h += [f"#define RN_VR_{c_name(v['name'])} {v['vr']}u" for v in variables]
    if name == "Driveline":
        for what in ("order", "amplitude", "phase"):
            vrs = [next(v["vr"] for v in variables if v["name"] == f"engine.{what}[{k}]")
                   for k in range(1, driveline.N_ORDERS + 1)]
            h.append(f"#define RN_VR_ENGINE_{what.upper()}S {{"
                     + ", ".join(f"{vr}u" for vr in vrs) + "}")
    h += ["", "/* constants of the Python modules */"]
    h += [f"#define {cname} {_c_number(value)}" for cname, value in CONSTANTS]
    h += ["", "extern const RnVariable RN_VARIABLES[RN_N_VARIABLES];",
          "/* the outputs in declaration order (rattle_kernel.c's output array) */",
          "extern const unsigned RN_OUTPUT_VR[RN_N_OUTPUTS];",
          "/* every variable, by name in Python's sort order (the FMU state's JSON) */",
          "extern const unsigned RN_SORTED_VR[RN_N_VARIABLES];", "", "#endif", ""]

    fmi_types = {"Real": "RN_REAL", "Integer": "RN_INTEGER", "Boolean": "RN_BOOLEAN",
             "String": "RN_STRING"}
    causalities = {"parameter": "RN_PARAMETER", "input": "RN_INPUT", "output": "RN_OUTPUT"}
    c = [f"/* GENERATED by drive_rattle_build/native.py for {name} -- do not edit. */",
         '#include "rattle_native.h"', ""]
    for v in variables:
        if v["choices"]:
            c.append(f"static const int CHOICES_{v['vr']}[] = {{"
                     + ", ".join(str(k) for k in v["choices"]) + "};")
    c += ["", "const RnVariable RN_VARIABLES[RN_N_VARIABLES] = {"]
    for v in variables:
        start = v["start"]
        start_real = float(start) if v["fmi_type"] == "Real" else 0.0
        start_int = int(start) if v["fmi_type"] in ("Integer", "Boolean") else 0
        start_string = _c_string(start) if v["fmi_type"] == "String" else "NULL"
        choices = f"CHOICES_{v['vr']}" if v["choices"] else "NULL"
        c.append(
            f"    {{{_c_string(v['name'])}, {fmi_types[v['fmi_type']]}, "
            f"{causalities[v['causality']]}, "
            f"{_c_string(v['unit'])}, {_c_number(start_real)}, {start_int}LL, {start_string}, "
            f"{int(v['min'] is not None)}, {int(v['max'] is not None)}, "
            f"{int(v['min_exclusive'])}, {int(v['max_exclusive'])}, "
            f"{_c_number(float(v['min'] or 0.0))}, {_c_number(float(v['max'] or 0.0))}, "
            f"{len(v['choices'])}, {choices}, {_c_string(v['allowed'])}, {v['group']}}},")
    c += ["};", "",
          "const unsigned RN_OUTPUT_VR[RN_N_OUTPUTS] = {"
          + ", ".join(f"{vr}u" for vr in outputs) + "};", "",
          "const unsigned RN_SORTED_VR[RN_N_VARIABLES] = {"
          + ", ".join(f"{v['vr']}u" for v in by_name) + "};", ""]
    return "\n".join(h), "\n".join(c)


def native_model_description(slave, guid: str) -> Element:
    """The native FMU's modelDescription: the pythonfmu FMU's, rendered from the same slave,
    with its GUID, no execution tool needed and the C sources listed."""
    root = model_description(slave)
    root.set("guid", guid)
    root.set("generationTool", GENERATION_TOOL)
    cosim = root.find("CoSimulation")
    cosim.set("needsExecutionTool", "false")
    files = SubElement(cosim, "SourceFiles")
    for source in C_SOURCES:
        SubElement(files, "File", {"name": source})
    return root


def interface_of(root: Element, reference: Element) -> Element:
    """``root`` with the attributes in which a native FMU differs from the pythonfmu FMU by
    design (generation tool, execution tool, source files) set back to ``reference``'s: what
    the template comparison sees."""
    copy = ElementTree.fromstring(ElementTree.tostring(root))
    copy.set("generationTool", reference.get("generationTool"))
    cosim = copy.find("CoSimulation")
    cosim.set("needsExecutionTool", reference.find("CoSimulation").get("needsExecutionTool"))
    for files in cosim.findall("SourceFiles"):
        cosim.remove(files)
    return copy




def stage_sources(slave, guid: str, folder: Path) -> list[Path]:
    """The C sources, headers and generated tables of one FMU in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    kernel.update_header()  # the kernel's generated layout, current
    header, source = render_tables(slave, guid)
    (folder / "rattle_native_tables.h").write_text(header, encoding="utf-8")
    (folder / "rattle_native_tables.c").write_text(source, encoding="utf-8")
    for name in C_SOURCES + HEADERS:
        if name not in GENERATED:
            shutil.copy2(NATIVE_DIR / name, folder / name)
    for name in FMI_HEADERS:
        shutil.copy2(fmi2_headers() / name, folder / name)
    return sorted(folder.iterdir())


def zig_cc(target: str) -> list[str]:
    """``python -m ziglang cc -target <target>`` (the ziglang package, a dependency)."""
    try:
        import ziglang  # noqa: F401
    except ImportError:
        raise RuntimeError(f"cross-compiling for {target} needs the ziglang package: "
                           "`pip install ziglang` (a dependency of this project)") from None
    return [sys.executable, "-m", "ziglang", "cc", "-target", target]


def compile_binary(sources: Path, out: Path, platform: str = "linux64",
                   cc: str | Sequence[str] = "gcc") -> Path:
    """Compile the FMU's sources in ``sources`` into the shared library ``out`` for
    ``platform`` (linux64 with ``cc``, win64 with ziglang's clang).  RuntimeError with the
    compiler's output on failure."""
    suffix, target = PLATFORMS[platform]
    compiler = zig_cc(target) if target else ([cc] if isinstance(cc, str) else list(cc))
    files = [str(sources / name) for name in C_SOURCES]
    if platform == "linux64":
        flags = [*CFLAGS, "-fPIC", "-shared", "-fvisibility=hidden"]
        libs = ["-lm"]
    else:
        flags = [*CFLAGS, "-shared"]
        libs = []
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="rattle_native_cc_") as tmp:
        target_file = Path(tmp) / f"{out.stem}{suffix}"
        cmd = [*compiler, *flags, "-I", str(sources), "-o", str(target_file), *files, *libs]
        try:
            run = subprocess.run(cmd, capture_output=True, text=True, check=False, cwd=tmp)
        except OSError as exc:
            raise RuntimeError(f"cannot run the C compiler {compiler[0]!r}: {exc}") from exc
        if run.returncode != 0 or not target_file.is_file():
            raise RuntimeError(f"compiling the native {out.stem} for {platform} failed (exit "
                               f"{run.returncode}): {' '.join(cmd)}\n{run.stdout}{run.stderr}")
        shutil.copy2(target_file, out)
    return out


NATIVE_HOW_TO_RUN = """<p>This FMU is implemented entirely in C: it needs no Python and no other
runtime where it runs. Binaries for linux64 (<code>binaries/linux64/{name}.so</code>) and win64
(<code>binaries/win64/{name}.dll</code>) are included, and the C sources
(<code>sources/</code>, listed in the modelDescription) compile for other platforms:</p>
<pre>cc -std=c99 -O2 -ffp-contract=off -fPIC -shared -I sources -o {name}.so sources/*.c -lm</pre>
<p>(<code>-ffp-contract=off</code> and no <code>-ffast-math</code>: the results are then those
of the Python reference, bit for bit, on the same C library.) In Python:</p>
<pre>from fmpy import simulate_fmu
result = simulate_fmu("{name}.fmu", output_interval=1e-4, stop_time=0.1)</pre>
"""


def package_native(name: str, out_dir: Path, cc: str | Sequence[str] = "gcc",
                   platforms: Sequence[str] = ("linux64", "win64"),
                   reference_files: Sequence[Path] = ()) -> Path:
    """Build ``out_dir/<name>.fmu``: sources, binaries for ``platforms``, modelDescription,
    resources (the marker and ``reference_files`` under resources/regression/) and
    documentation.  Returns its path."""
    cls = slave_class(name)
    slave = cls(instance_name="native-build")
    guid = "{" + str(uuid.uuid4()) + "}"
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fmu = out_dir / f"{name}.fmu"
    with tempfile.TemporaryDirectory(prefix=f"native_{name}_") as tmp:
        tmp = Path(tmp)
        sources = tmp / "sources"
        stage_sources(slave, guid, sources)
        binaries = {p: compile_binary(sources, tmp / "binaries" / p / name, p, cc)
                    for p in platforms}
        root = native_model_description(slave, guid)
        xml = ElementTree.tostring(root, encoding="unicode", xml_declaration=False)
        page = html_page(cls, NATIVE_HOW_TO_RUN.format(name=name),
                         build_note="implemented in C (no Python at run time), binaries for "
                                    f"{' and '.join(platforms)} and C sources")
        part = fmu.with_name(f".{fmu.name}.{os.getpid()}.part")
        with zipfile.ZipFile(part, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml",
                       '<?xml version="1.0" encoding="UTF-8"?>\n' + xml + "\n")
            for platform, binary in binaries.items():
                info = zipfile.ZipInfo(f"binaries/{platform}/{name}{PLATFORMS[platform][0]}")
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o100755 << 16
                z.writestr(info, binary.read_bytes())
            for source in sorted(sources.iterdir()):
                z.write(source, f"sources/{source.name}")
            z.writestr(f"resources/{RESOURCE_MARKER}", f"{name}\n")
            for ref in reference_files:
                z.write(ref, f"resources/regression/{Path(ref).name}")
            z.writestr("documentation/index.html", page)
        os.replace(part, fmu)
    return fmu


def check_interface(fmu: Path) -> None:
    """BuildError unless the native FMU's interface is the committed template's (the
    pythonfmu FMU's, apart from the generation tool, execution tool and source files)."""
    with zipfile.ZipFile(fmu) as z:
        root = ElementTree.fromstring(z.read("modelDescription.xml"))
    name = root.find("CoSimulation").get("modelIdentifier")
    reference = model_description(slave_class(name)(instance_name="native-check"))
    if not templates.matches_template(name, interface_of(root, reference)):
        raise BuildError(
            f"native {name}: the interface differs from {templates.template_path(name)}; the "
            "native FMUs render it from the same specs as the pythonfmu FMUs, so this is a "
            "build defect")


def build_native(out_dir: Path = DIST / NATIVE_SUBDIR, use_fmutool: bool = True,
                 platforms: Sequence[str] = tuple(PLATFORMS),
                 models: Sequence[str] = MODELS) -> list[Path]:
    """Build the native FMUs into ``out_dir``, hold each against its committed template and
    validate it (fmpy's validate_fmu, ``fmutool -check`` with ``use_fmutool``).  BuildError
    with the reason on any failure."""
    from drive_rattle_cosim.regression import reference_files

    fmus = []
    try:
        for name in models:
            refs = reference_files(name)
            refs = refs if all(f.is_file() for f in refs) else []  # as the pythonfmu FMU
            fmu = package_native(name, Path(out_dir), c_compiler(), platforms, refs)
            check_interface(fmu)
            validate(fmu, use_fmutool)
            fmus.append(fmu)
    except BuildError:
        raise
    except RuntimeError as err:  # a compiler's or a check's failure, with its reason
        raise BuildError(str(err)) from None
    return fmus
