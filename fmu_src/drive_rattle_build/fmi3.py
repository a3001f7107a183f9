"""FMI 3.0 FMUs: GearMeshRattle and Driveline as the model library (``fmu_src/rattle_model``)
under its FMI 3.0 co-simulation face (``fmu_src/fmi3/fmi3_functions.c``), with no Python at run
time, built for x86_64-linux, x86_64-windows and aarch64-linux (``platforms.FMI3_SHIPPED``; more
on request) and shipped with their C sources, an icon and a terminal per shaft
(``terminals``), into ``<out>/fmi3/`` (docs/fmi3.md).

The same model as the FMI 2.0 native FMUs (``native``): the library's sources as they are, a
face that holds no physics, ``rattle_fmi_common.c`` (what every FMI layer shares: the resources
folder, the marker file, printable paths, the state envelope) and the generated
``rattle_fmu_config.h`` (``native.render_config``: the unit, the model identifier, the
instantiation token).  The FMU ships them in ``sources/`` with the FMI 3.0 headers (as fmpy
bundles them) and ``sources/buildDescription.xml`` (FMI 3.0's list of the sources), so that
they compile alone.  Only the ``fmi3`` functions are exported, all of them (those of what
these units do not have refuse with a message).

The instantiation token is the GUID scheme of the other FMUs (``identity.fmu_guid``: model,
flavour "fmi3", the library's sources and the face's).  The modelDescription is rendered by
``model_description_fmi3`` and held against the committed
``modelDescription_templates/fmi3/<Model>.xml`` (rewritten with ``--update-templates``).

``build_fmi3(out_dir)`` compiles, packs and validates both FMUs.  Build time only: fmpy (the
FMI 3.0 headers, validate_fmu), a C compiler for x86_64-linux (``compiler.c_compiler``) and the
``ziglang`` package for the other platforms (``platforms``).
"""

from __future__ import annotations

import difflib
import hashlib
import os
import shutil
import tempfile
import zipfile
from collections.abc import Sequence
from pathlib import Path
from xml.dom.minidom import parseString
from xml.etree import ElementTree
from xml.etree.ElementTree import Element, SubElement

from drive_rattle.catalog import UNITS
from drive_rattle.interface import MODELS

from . import model_description_fmi3, model_tables, templates
from .compiler import BuildError, c_compiler
from .documentation import LICENSE_ENTRY, html_page, license_text
from .fmu import validate
from .identity import fmu_guid
from .library import source_flags
from .native import CONFIG_HEADER, RESOURCE_MARKER, model_sources, render_config
from .paths import DIST, FMI3_SOURCE, FMI_COMMON_SOURCE, TEMPLATES, model_files
from .platforms import (
    FMI3_SHIPPED,
    PLATFORMS,
    binaries_html,
    binary_member,
    compile_face_binary,
    cross_compile_html,
    write_binary,
)
from .terminals import add_terminals_and_icon

#: The FMI 3.0 face and what it shares with the other FMI layers, compiled with the library.
GLUE_SOURCES = ("fmi3_functions.c", "rattle_fmi_common.c")
GLUE_HEADERS = ("rattle_fmi_common.h",)
#: The FMI 3.0 headers, as the standard ships them (fmpy bundles them).
FMI_HEADERS = ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")
#: Where the FMI 3.0 FMUs go, below the output folder.
FMI3_SUBDIR = "fmi3"
#: The committed normalised modelDescriptions of the FMI 3.0 FMUs.
FMI3_TEMPLATES = TEMPLATES / "fmi3"
GENERATION_TOOL = "drive-rattle-build (native C, FMI 3.0)"
#: The flags the sources must be compiled with for the shipped binaries' numbers (IEEE, no
#: contraction), as buildDescription.xml states them.
SOURCE_COMPILER_OPTIONS = "-std=c99 -O2 -ffp-contract=off"


# ------------------------------------------------------------------ sources
def fmi3_headers() -> Path:
    """The folder of the official FMI 3.0 headers as fmpy ships them (``fmpy/c-code``)."""
    import fmpy

    folder = Path(fmpy.__file__).resolve().parent / "c-code"
    missing = [name for name in FMI_HEADERS if not (folder / name).is_file()]
    if missing:
        raise BuildError(f"fmpy's FMI 3.0 headers are missing: no {', '.join(missing)} in "
                         f"{folder} (install fmpy 0.3.x, which ships them)")
    return folder


def glue_files() -> list[Path]:
    """The FMI 3.0 face's sources and headers."""
    return [FMI3_SOURCE / "fmi3_functions.c", FMI_COMMON_SOURCE / "rattle_fmi_common.c",
            FMI_COMMON_SOURCE / "rattle_fmi_common.h"]


def glue_id() -> str:
    """The hash of the face's sources (by name and content): part of the token."""
    digest = hashlib.sha256()
    for path in glue_files():
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def fmi3_token(model: str) -> str:
    """The instantiation token of the FMI 3.0 ``model``: the GUID scheme of the other FMUs,
    from the library's sources and the face's."""
    return fmu_guid(model, "fmi3", glue_id())


def source_files() -> list[str]:
    """The C files of an FMU's sources/ that are compiled (buildDescription.xml's order)."""
    return [p.name for p in model_files("*.c")] + list(GLUE_SOURCES)


def build_description(model: str) -> Element:
    """``sources/buildDescription.xml``: one build configuration of the C99 sources."""
    root = Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    config = SubElement(root, "BuildConfiguration", {
        "modelIdentifier": model,
        "description": "the model library and its FMI 3.0 face; IEEE arithmetic without "
                       "contraction (no -ffast-math) gives the shipped binaries' numbers"})
    files = SubElement(config, "SourceFileSet", {"language": "C99",
                                                 "compilerOptions": SOURCE_COMPILER_OPTIONS})
    for name in source_files():
        SubElement(files, "SourceFile", {"name": name})
    return root


def stage_sources(model: str, token: str, folder: Path) -> list[Path]:
    """The C sources and headers of one FMU in ``folder`` (flat): the model library, the
    face, the FMI 3.0 headers, the generated config header and buildDescription.xml."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    model_tables.update()  # the library's tables, current with the specs
    for path in (*model_sources(), *glue_files()):
        shutil.copy2(path, folder / path.name)
    for name in FMI_HEADERS:
        shutil.copy2(fmi3_headers() / name, folder / name)
    (folder / CONFIG_HEADER).write_text(render_config(model, token, "fmi3_functions.c"),
                                        encoding="utf-8")
    (folder / "buildDescription.xml").write_text(
        xml_text(build_description(model)), encoding="utf-8")
    return sorted(folder.iterdir())


def compile_binary(sources: Path, out: Path, platform: str = "x86_64-linux",
                   cc: str | Sequence[str] | None = None,
                   extra_flags: Sequence[str] = ()) -> Path:
    """Compile the FMU's ``sources`` folder (:func:`stage_sources`) into the shared library
    ``out`` for ``platform`` (``platforms.compile_for``); only the fmi3 functions exported;
    BuildError with the compiler's output on failure or on any warning (-Werror)."""
    return compile_face_binary(platform, sources, GLUE_SOURCES, out, cc,
                               ["-Werror", *source_flags(), *extra_flags],
                               f"the FMI 3.0 {Path(out).stem}")


# ------------------------------------------------------------------ modelDescription
def xml_text(root: Element) -> str:
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            + ElementTree.tostring(root, encoding="unicode") + "\n")


def render_model_description(model: str, token: str, generation_time: str | None = None
                             ) -> Element:
    return model_description_fmi3.render(model, token, GENERATION_TOOL, generation_time)


def normalised_xml(root: Element) -> str:
    """Pretty-printed XML with the per-build attributes (token, date) blanked: what the
    committed template holds."""
    copy = Element(root.tag, dict(root.attrib))
    copy.extend(list(root))
    copy.set("instantiationToken", "{TOKEN}")
    copy.set("generationDateAndTime", "DATE")
    text = parseString(ElementTree.tostring(copy, "unicode")).documentElement.toprettyxml(
        indent="  ")
    return "\n".join(line for line in text.splitlines() if line.strip()) + "\n"


def template_path(model: str) -> Path:
    return FMI3_TEMPLATES / f"{model}.xml"


def hold_template(model: str, root: Element, update: bool = False) -> None:
    """Hold the FMI 3.0 modelDescription ``root`` against its committed template (with
    ``update``: rewrite the template).  BuildError with the diff when they differ."""
    path = template_path(model)
    mine = normalised_xml(root)
    if update:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f"{templates.TEMPLATE_NOTE}\n{mine}", encoding="utf-8")
        return
    text = templates.template_body(path.read_text(encoding="utf-8")) if path.is_file() else ""
    if text != mine:
        diff = list(difflib.unified_diff(text.splitlines(), mine.splitlines(),
                                         f"{FMI3_TEMPLATES.parent.name}/fmi3/{model}.xml",
                                         f"FMI 3.0 {model}", lineterm="", n=1))
        shown = "\n".join(diff[:60]) + ("\n..." if len(diff) > 60 else "")
        raise BuildError(
            f"FMI 3.0 {model}: the interface differs from {path} (review the change, rewrite "
            f"the templates with `drive-rattle-build --update-templates` and commit their "
            f"diff):\n{shown}")


# ------------------------------------------------------------------ packing
FMI3_HOW_TO_RUN = """<p>This is an FMI 3.0 co-simulation FMU implemented entirely in C: it needs
no Python and no other runtime where it runs. {binaries}, and the C sources
(<code>sources/</code>, listed in <code>sources/buildDescription.xml</code>) compile for other
platforms:</p>
<pre>cc -std=c99 -O2 -ffp-contract=off -fPIC -shared -I sources -o {name}.so sources/*.c -lm</pre>
{cross_compile}
<p>Types: the table's Real is an FMI 3.0 Float64, Integer an Int32, except the integer codes
with named choices, which are Enumerations (set and read with fmi3SetInt64/fmi3GetInt64).
The independent variable is <code>time</code>. Warnings are logged when logging is on
(category logStatusWarning or logAll); errors always. In Python:</p>
<pre>from fmpy import simulate_fmu
result = simulate_fmu("{name}.fmu", output_interval=1e-4, stop_time=0.1)</pre>
"""


def documentation_page(model: str, platforms: Sequence[str]) -> str:
    """documentation/index.html: the interface page of the FMUs in FMI 3.0's words."""
    page = html_page(UNITS[model], FMI3_HOW_TO_RUN.format(
                         name=model, binaries=binaries_html(model, 3, platforms),
                         cross_compile=cross_compile_html(model)),
                     build_note="implemented in C (no Python at run time), binaries for "
                                f"{' and '.join(platforms)} and C sources")
    page = page.replace("FMI 2.0 co-simulation", "FMI 3.0 co-simulation").replace("fmi2",
                                                                                  "fmi3")
    if "FMI 2.0" in page or "fmi2" in page:
        raise BuildError(f"{model}: the FMI 3.0 documentation page still speaks of FMI 2.0")
    return page


def package_fmi3(model: str, out_dir: Path, cc: str | Sequence[str] | None = None,
                 platforms: Sequence[str] = FMI3_SHIPPED,
                 reference_files: Sequence[Path] = ()) -> Path:
    """Build ``out_dir/<model>.fmu``: sources (with buildDescription.xml), binaries for
    ``platforms``, modelDescription, resources (the marker and ``reference_files`` under
    resources/regression/) and documentation.  Returns its path."""
    token = fmi3_token(model)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fmu = out_dir / f"{model}.fmu"
    with tempfile.TemporaryDirectory(prefix=f"fmi3_{model}_") as tmp:
        tmp = Path(tmp)
        sources = tmp / "sources"
        stage_sources(model, token, sources)
        binaries = {binary_member(model, 3, p): compile_binary(
            sources, tmp / p / f"{model}{PLATFORMS[p].suffix}", p, cc) for p in platforms}
        xml = xml_text(render_model_description(model, token))
        part = fmu.with_name(f".{fmu.name}.{os.getpid()}.part")
        with zipfile.ZipFile(part, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", xml)
            for member, binary in binaries.items():
                write_binary(z, member, binary.read_bytes())
            for source in sorted(sources.iterdir()):
                z.write(source, f"sources/{source.name}")
            z.writestr(f"resources/{RESOURCE_MARKER}", f"{model}\n")
            for ref in reference_files:
                z.write(ref, f"resources/regression/{Path(ref).name}")
            z.writestr("documentation/index.html", documentation_page(model, platforms))
            z.writestr(LICENSE_ENTRY, license_text())
            add_terminals_and_icon(z, model)
        os.replace(part, fmu)
    return fmu


def build_fmi3(out_dir: Path = DIST / FMI3_SUBDIR, use_fmutool: bool = True,
               platforms: Sequence[str] = FMI3_SHIPPED, models: Sequence[str] = MODELS,
               check_template: bool = True, update_templates: bool = False) -> list[Path]:
    """Build the FMI 3.0 FMUs into ``out_dir``, hold each against its committed template
    (``check_template``; ``update_templates`` rewrites them) and validate it (fmpy's
    validate_fmu, ``fmutool -check`` with ``use_fmutool``).  BuildError on any failure."""
    from drive_rattle_cosim.regression import reference_files

    fmus = []
    cc = c_compiler()
    for model in models:
        refs = reference_files(model)
        refs = refs if all(f.is_file() for f in refs) else []
        fmu = package_fmi3(model, Path(out_dir), cc, platforms, refs)
        if check_template or update_templates:
            with zipfile.ZipFile(fmu) as z:
                root = ElementTree.fromstring(z.read("modelDescription.xml"))
            hold_template(model, root, update=update_templates)
        validate(fmu, use_fmutool)
        fmus.append(fmu)
    return fmus
