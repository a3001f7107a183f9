"""Interface documentation of the FMUs, generated from the same specs as the registration and
the modelDescription: documentation/index.html inside each FMU and the Markdown tables of
docs/fmi.md."""

from __future__ import annotations

import html

from drive_rattle.catalog import UNITS, UnitSpec
from drive_rattle.interface import DEFAULT_EXPERIMENT, MODELS
from drive_rattle.parameters import specs
from drive_rattle.units import input_starts

from .compiler import BuildError
from .model_description import enumeration
from .paths import CHECKOUT, FMI_DOCS, ROOT

#: Where the FMI standard's FMU layout places the licenses of an FMU's contents: the folder
#: ``documentation/licenses/`` with the entry point ``license.txt`` (or .html).
LICENSE_ENTRY = "documentation/licenses/license.txt"


def license_text() -> str:
    """The project's license (LICENSE of the checkout, or of the installed distribution)."""
    if CHECKOUT:
        return (ROOT / "LICENSE").read_text(encoding="utf-8")
    from importlib.metadata import distribution

    text = distribution("drive-rattle").read_text("licenses/LICENSE")
    if text is None:
        raise BuildError("the installed drive-rattle carries no licenses/LICENSE: reinstall it")
    return text


def interface_rows(unit: UnitSpec) -> list[tuple[str, str, str, str, str, str]]:
    """``(name, causality, type, unit, start/limits, description)`` for every public variable
    of ``unit`` (the inputs' start values are the model library's)."""
    rows = []
    starts = input_starts(unit.kind)
    for _attr, spec in specs(unit.parameters):
        limits = spec.allowed() if spec.fmi_type in ("Real", "Integer") else ""
        start = repr(spec.default) if spec.fmi_type != "Boolean" else str(spec.default).lower()
        fmi_type = spec.fmi_type
        declared = enumeration(spec)
        if declared is not None:  # the codes by their item names
            fmi_type = f"Enumeration ({declared.type_name})"
            limits = "one of " + ", ".join(f"{i.value} = {i.name}" for i in declared.items)
        allowed = f"{start}; {limits}".rstrip("; ")
        rows.append((spec.name, "parameter", fmi_type, spec.unit, allowed, spec.description))
    for spec in unit.inputs:
        allowed = repr(starts[spec.name])
        if spec.minimum is not None:
            allowed += f"; [{spec.minimum:g}, {spec.maximum:g}] {spec.unit}"
        rows.append((spec.name, "input", spec.fmi_type, spec.unit, allowed, spec.description))
    for spec in unit.outputs:
        rows.append((spec.name, "output", spec.fmi_type, spec.unit, "", spec.description))
    return rows


def markdown_interface(unit: UnitSpec) -> str:
    """Markdown table of the interface."""
    head = "| name | causality | type | unit | start; allowed | description |\n"
    head += "|---|---|---|---|---|---|\n"
    body = "".join(
        "| `" + r[0] + "` | " + " | ".join(c.replace("|", "\\|") for c in r[1:]) + " |\n"
        for r in interface_rows(unit))
    return head + body


def html_page(unit: UnitSpec, how_to_run: str,
              build_note: str = "built with pythonfmu and a status shim, the model a C "
                                "library; linux64 only (on Windows use the native FMU of the "
                                "same name, dist/native/)") -> str:
    """documentation/index.html of the FMU (``build_note``: how this flavour is built)."""
    rows = "\n".join(
        "<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>"
        for r in interface_rows(unit))
    exp = DEFAULT_EXPERIMENT
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{unit.model}</title>
<style>body{{font-family:sans-serif;max-width:70em}}td,th{{border:1px solid #ccc;padding:2px 6px;
vertical-align:top}}table{{border-collapse:collapse}}code{{background:#f4f4f4}}</style></head>
<body>
<h1>{unit.model}</h1>
<p>{html.escape(unit.description)}</p>
<p>FMI 2.0 co-simulation, {build_note}. Default
experiment: start {exp['startTime']} s, stop {exp['stopTime']} s, communication step
{exp['stepSize']} s. All values are SI; display units are declared in the modelDescription.</p>
<h2>How to run</h2>
{how_to_run}
<h2>Interface</h2>
<table><tr><th>name</th><th>causality</th><th>type</th><th>unit</th><th>start; allowed</th>
<th>description</th></tr>
{rows}
</table>
<h2>Behaviour on bad input</h2>
<p>Invalid parameters make <code>fmi2ExitInitializationMode</code> return fmi2Error; a
non-finite input, a non-positive or too large step, or a communication point that does not
continue the last step make <code>fmi2DoStep</code> return fmi2Error. The message, naming the
variable, its value and what is allowed, is sent to the logger even with debug logging off, and
a rejected call leaves the instance's state as it was.</p>
</body></html>
"""


HOW_TO_RUN = """<p>This FMU runs on Linux (x86-64) only: it has a <code>binaries/linux64</code>
binary and no other. <b>On Windows, or in a tool without Python, use the native FMU of the same
name</b> (<code>dist/native/{name}.fmu</code>: the same model, interface and numbers, in C).
This one needs a Python 3 interpreter (3.10 or newer) on the machine where it runs; its Python
uses only the standard library, pythonfmu's runtime is bundled, and the model is a C library
(<code>resources/drive_rattle/rattle_model.so</code>). Inside a Python host (fmpy, libcosimpy)
the host's interpreter is used:</p>
<pre>from fmpy import simulate_fmu
result = simulate_fmu("{name}.fmu", output_interval=1e-4, stop_time=0.1)</pre>
<p>A native host (a C/C++ simulation tool) on Linux must load libpython into the process first
(<code>LD_PRELOAD</code> set to the output of <code>python3 -c "import os, sysconfig as s;
print(os.path.join(s.get_config_var('LIBDIR'), s.get_config_var('INSTSONAME')))"</code>, run
with the <code>python3</code> that is first on <code>PATH</code>). Do not unpack the FMU under a
path that needs escaping beyond what the shim decodes (any %XX is decoded).</p>
"""


def interface_docs(text: str) -> str:
    """``text`` (docs/fmi.md) with each ``<!-- BEGIN <Model> interface -->`` ...
    ``<!-- END ... -->`` block replaced by the interface table of the unit ``<Model>``.
    BuildError when a marker is missing."""
    for name in MODELS:
        begin, end = f"<!-- BEGIN {name} interface -->", f"<!-- END {name} interface -->"
        head, _, rest = text.partition(begin)
        _, _, tail = rest.partition(end)
        if not rest:
            raise BuildError(f"{FMI_DOCS} lacks the marker {begin}")
        text = f"{head}{begin}\n{markdown_interface(UNITS[name])}{end}{tail}"
    return text
