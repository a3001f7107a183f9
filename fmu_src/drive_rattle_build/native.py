"""Native FMUs: GearMeshRattle and Driveline as the model library (``fmu_src/rattle_model``)
under its FMI 2.0 face (``fmu_src/fmi2/fmi2_functions.c``), with no Python at run time, built
for linux64 and win64 (``platforms.FMI2_SHIPPED``; more on request) and shipped with their C
sources.

Each FMU's binary is the one model compiled with the glue: the library's sources, the glue,
``rattle_fmi_common.c`` (what the glue shares with the pythonfmu FMUs' status shim) and a small
generated header, ``rattle_fmu_config.h``, naming the unit (its kind), the model identifier and
the GUID.  The FMU ships them all in ``sources/`` (listed in ``<SourceFiles>``) with the FMI
2.0 headers, so that they compile alone for other platforms.  Only the ``fmi2`` functions are
exported.

The GUID is derived from the model, the flavour, the library's sources and the glue's
(``identity.fmu_guid``): a state saved by one build restores in another build of the same
sources.  The modelDescription is rendered from the specs (:func:`render_model_description`)
and its interface held against the committed ``modelDescription_templates/``.

``build_native(out_dir)`` compiles, packs and validates both FMUs into ``out_dir``
(``dist/native`` from ``drive-rattle-build``).  Build time only: it needs fmpy (the FMI 2.0
headers, validate_fmu), a C compiler for linux64 (``compiler.c_compiler``) and the ``ziglang``
package for the other platforms (``platforms``).
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
from xml.etree import ElementTree
from xml.etree.ElementTree import Element

from drive_rattle.catalog import UNITS
from drive_rattle.interface import (
    DRIVELINE,
    MESH,
    MODELS,
)

from . import model_description, model_tables, templates
from .compiler import BuildError, c_compiler
from .documentation import LICENSE_ENTRY, html_page, license_text
from .fmu import validate
from .icon import model_png
from .identity import fmu_guid
from .library import source_flags
from .paths import DIST, FMI2_SOURCE, FMI_COMMON_SOURCE, TEMPLATES, model_files
from .platforms import (
    FMI2_SHIPPED,
    PLATFORMS,
    binaries_html,
    binary_member,
    compile_face_binary,
    cross_compile_html,
    write_binary,
)
from .shim import fmi2_headers

#: The FMI 2.0 face, compiled with the model library into every native FMU (flat in the FMU's
#: sources/; in the checkout rattle_fmi_common.* are in fmu_src/fmi_common/, the rest in fmi2/).
GLUE_SOURCES = ("fmi2_functions.c", "rattle_fmi_common.c", "rattle_fmi2_common.c")
GLUE_HEADERS = ("rattle_fmi_common.h", "rattle_fmi2_common.h")
#: The glue's files that every FMI face shares (paths.FMI_COMMON_SOURCE).
COMMON_GLUE = ("rattle_fmi_common.c", "rattle_fmi_common.h")
#: The generated header of each FMU: its unit kind, model identifier and GUID.
CONFIG_HEADER = "rattle_fmu_config.h"
#: The FMI 2.0 headers, as the standard ships them (fmpy bundles them).
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
#: The file in resources/ that identifies the FMU (the native counterpart of pythonfmu's
#: slavemodule.txt): its model identifier on the first line.
RESOURCE_MARKER = "model_identifier.txt"
#: The unit kind (RmKind of rattle_model.h) of each model.
KINDS = {MESH: "RM_MESH", DRIVELINE: "RM_DRIVELINE"}
GENERATION_TOOL = "drive-rattle-build (native C)"
#: Where the native FMUs go, below the output folder.
NATIVE_SUBDIR = "native"


# ------------------------------------------------------------------ sources
def model_sources() -> list[Path]:
    """The model library's C sources and headers that ship (the generated tables included;
    the test-only probes left out: ``paths.TEST_ONLY_SOURCES``)."""
    return model_files("*.[ch]")


def glue_files() -> list[Path]:
    """The FMI 2.0 face's sources and header."""
    return [(FMI_COMMON_SOURCE if name in COMMON_GLUE else FMI2_SOURCE) / name
            for name in (*GLUE_SOURCES, *GLUE_HEADERS)]


def glue_id() -> str:
    """The hash of the glue's sources (by name and content): part of the GUID."""
    digest = hashlib.sha256()
    for path in glue_files():
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def native_guid(model: str) -> str:
    """The GUID of the native ``model``: from the library's sources and the glue's."""
    return fmu_guid(model, "native", glue_id())


def source_files() -> list[str]:
    """The C files of an FMU's sources/ that are compiled, in <SourceFiles> order."""
    return [p.name for p in model_files("*.c")] + list(GLUE_SOURCES)


def render_config(model: str, guid: str, face: str = "fmi2_functions.c") -> str:
    """The text of ``rattle_fmu_config.h`` for ``model`` and its FMI ``face``."""
    for text, what in ((model, "model identifier"), (guid, "GUID")):
        if not text.isascii() or any(c in text for c in '"\\?') or not text.isprintable():
            raise BuildError(f"{what} {text!r} cannot be a C string literal")
    return (f"/* GENERATED by drive_rattle_build/native.py for {model} -- do not edit.\n"
            f" * The unit of this FMU, its model identifier and GUID ({face}). */\n"
            "#ifndef RATTLE_FMU_CONFIG_H\n#define RATTLE_FMU_CONFIG_H\n\n"
            f"#define RATTLE_UNIT_KIND {KINDS[model]}\n"
            f'#define RATTLE_MODEL_IDENTIFIER "{model}"\n'
            f'#define RATTLE_GUID "{guid}"\n\n#endif\n')


def stage_sources(model: str, guid: str, folder: Path) -> list[Path]:
    """The C sources and headers of one FMU in ``folder`` (flat): the model library, the
    glue, the FMI 2.0 headers and the generated config header."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    model_tables.update()  # the library's tables, current with the specs
    for path in (*model_sources(), *glue_files()):
        shutil.copy2(path, folder / path.name)
    for name in FMI_HEADERS:
        shutil.copy2(fmi2_headers() / name, folder / name)
    (folder / CONFIG_HEADER).write_text(render_config(model, guid), encoding="utf-8")
    return sorted(folder.iterdir())


def compile_binary(sources: Path, out: Path, platform: str = "x86_64-linux",
                   cc: str | Sequence[str] | None = None,
                   extra_flags: Sequence[str] = ()) -> Path:
    """Compile the FMU's ``sources`` folder (:func:`stage_sources`) into the shared library
    ``out`` for ``platform`` (an FMI 3.0 platform tuple, ``platforms.compile_for``: the build
    machine's with ``cc``, others with ziglang's clang); only the fmi2 functions exported.
    BuildError with the compiler's output on failure or on any warning (-Werror: the sources
    compile warning-free)."""
    return compile_face_binary(platform, sources, GLUE_SOURCES, out, cc,
                               ["-Werror", *source_flags(), *extra_flags],
                               f"the native {Path(out).stem}")


# ------------------------------------------------------------------ modelDescription
def render_model_description(model: str, guid: str, generation_time: str | None = None
                             ) -> Element:
    """The native FMU's modelDescription (``model_description.render``: the same rendering as
    the pythonfmu FMU's, no execution tool, the C sources listed)."""
    return model_description.render(model, guid, GENERATION_TOOL, needs_execution_tool=False,
                                    sources=source_files(), generation_time=generation_time)


def interface_of(root: Element, reference: Element) -> Element:
    """``root`` with the attributes in which a native FMU differs from the pythonfmu FMU by
    design (generation tool, execution tool, source files) set to ``reference``'s: what the
    template comparison sees."""
    copy = ElementTree.fromstring(ElementTree.tostring(root))
    copy.set("generationTool", reference.get("generationTool"))
    cosim = copy.find("CoSimulation")
    cosim.set("needsExecutionTool", reference.find("CoSimulation").get("needsExecutionTool"))
    for files in cosim.findall("SourceFiles"):
        cosim.remove(files)
    return copy


def interface_diff(model: str, root: Element) -> list[str]:
    """The unified diff from the committed template of ``model`` to the interface of the
    native modelDescription ``root`` (empty when they match)."""
    path = templates.template_path(model)
    if not path.is_file():
        return [f"no template {path}"]
    text = templates.template_body(path.read_text(encoding="utf-8"))
    reference = ElementTree.fromstring(text)
    mine = templates.normalised_xml(interface_of(root, reference))
    return list(difflib.unified_diff(text.splitlines(), mine.splitlines(),
                                     f"{TEMPLATES.name}/{model}.xml", f"native {model}",
                                     lineterm="", n=1))


# ------------------------------------------------------------------ packing
NATIVE_HOW_TO_RUN = """<p>This FMU is implemented entirely in C: it needs no Python and no other
runtime where it runs. {binaries}, and the C sources (<code>sources/</code>, listed in the
modelDescription) compile for other platforms:</p>
<pre>cc -std=c99 -O2 -ffp-contract=off -fPIC -shared -I sources -o {name}.so sources/*.c -lm</pre>
{cross_compile}
<p>(<code>-ffp-contract=off</code> and no <code>-ffast-math</code>: the results are then those
of the shipped binary, bit for bit, on the same C library.) In Python:</p>
<pre>from fmpy import simulate_fmu
result = simulate_fmu("{name}.fmu", output_interval=1e-4, stop_time=0.1)</pre>
"""


def package_native(model: str, out_dir: Path, cc: str | Sequence[str] | None = None,
                   platforms: Sequence[str] = FMI2_SHIPPED,
                   reference_files: Sequence[Path] = ()) -> Path:
    """Build ``out_dir/<model>.fmu``: sources, binaries for ``platforms``, modelDescription,
    resources (the marker and ``reference_files`` under resources/regression/) and
    documentation.  Returns its path."""
    guid = native_guid(model)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fmu = out_dir / f"{model}.fmu"
    with tempfile.TemporaryDirectory(prefix=f"native_{model}_") as tmp:
        tmp = Path(tmp)
        sources = tmp / "sources"
        stage_sources(model, guid, sources)
        binaries = {binary_member(model, 2, p): compile_binary(
            sources, tmp / p / f"{model}{PLATFORMS[p].suffix}", p, cc) for p in platforms}
        root = render_model_description(model, guid)
        xml = ElementTree.tostring(root, encoding="unicode", xml_declaration=False)
        folders = [PLATFORMS[p].folder(2) for p in platforms]
        page = html_page(UNITS[model], NATIVE_HOW_TO_RUN.format(
                             name=model, binaries=binaries_html(model, 2, platforms),
                             cross_compile=cross_compile_html(model)),
                         build_note="implemented in C (no Python at run time), binaries for "
                                    f"{' and '.join(folders)} and C sources")
        part = fmu.with_name(f".{fmu.name}.{os.getpid()}.part")
        with zipfile.ZipFile(part, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml",
                       '<?xml version="1.0" encoding="UTF-8"?>\n' + xml + "\n")
            for member, binary in binaries.items():
                write_binary(z, member, binary.read_bytes())
            for source in sorted(sources.iterdir()):
                z.write(source, f"sources/{source.name}")
            z.writestr(f"resources/{RESOURCE_MARKER}", f"{model}\n")
            for ref in reference_files:
                z.write(ref, f"resources/regression/{Path(ref).name}")
            z.writestr("documentation/index.html", page)
            z.writestr(LICENSE_ENTRY, license_text())
            z.writestr("model.png", model_png())
        os.replace(part, fmu)
    return fmu


def check_interface(fmu: Path) -> None:
    """BuildError unless the native FMU's interface is the committed template's (the
    pythonfmu FMU's, apart from the generation tool, execution tool and source files), with
    the diff."""
    with zipfile.ZipFile(fmu) as z:
        root = ElementTree.fromstring(z.read("modelDescription.xml"))
    model = root.find("CoSimulation").get("modelIdentifier")
    diff = interface_diff(model, root)
    if diff:
        shown = "\n".join(diff[:60]) + ("\n..." if len(diff) > 60 else "")
        raise BuildError(
            f"native {model}: the interface differs from {templates.template_path(model)} "
            "(review the change, rewrite the templates with `drive-rattle-build "
            f"--update-templates` and commit their diff):\n{shown}")


def build_native(out_dir: Path = DIST / NATIVE_SUBDIR, use_fmutool: bool = True,
                 platforms: Sequence[str] = FMI2_SHIPPED,
                 models: Sequence[str] = MODELS, check_template: bool = True) -> list[Path]:
    """Build the native FMUs into ``out_dir``, hold each against its committed template (with
    ``check_template``) and validate it (fmpy's validate_fmu, ``fmutool -check`` with
    ``use_fmutool``).  BuildError with the reason on any failure."""
    from drive_rattle_cosim.regression import reference_files

    fmus = []
    cc = c_compiler()
    for model in models:
        refs = reference_files(model)
        refs = refs if all(f.is_file() for f in refs) else []
        fmu = package_native(model, Path(out_dir), cc, platforms, refs)
        if check_template:
            check_interface(fmu)
        validate(fmu, use_fmutool)
        fmus.append(fmu)
    return fmus
