"""text.c, the library's formatter: a message is one format string at its check, its numbers
written the same in every locale -- %r the shortest text that reads back to the double (the
digits Python's repr() chooses) and %.Nr N significant digits in C's %g form (Python's own %g,
which no locale changes, is the reference) -- under the C locale, German
(decimal comma) and Pashto (a two-byte decimal separator); and no message of the sources uses
printf's floating conversions, which follow LC_NUMERIC."""

from __future__ import annotations

import os
import random
import re
import shutil
import struct
import subprocess
from decimal import Decimal
from pathlib import Path

import pytest

from drive_rattle_build.compiler import c_compiler
from drive_rattle_build.paths import MODEL_SOURCE, SOURCE

DRIVER = Path(__file__).with_name("text_driver.c")
#: Locales with another decimal separator than '.': a comma, and the two bytes of U+066B.
LOCALES = ("de_DE.UTF-8", "ps_AF.UTF-8")


@pytest.fixture(scope="module")
def driver(tmp_path_factory):
    """(the driver compiled with text.c alone, its environment with LOCPATH)."""
    folder = tmp_path_factory.mktemp("text")
    exe = folder / "text_driver"
    subprocess.run([c_compiler(), "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror",
                    "-I", str(MODEL_SOURCE), "-o", str(exe), str(DRIVER),
                    str(MODEL_SOURCE / "text.c"), "-lm"], check=True, capture_output=True,
                   timeout=300)
    return exe, folder


def compiled_locale(folder: Path, name: str) -> dict:
    """The environment in which ``name`` exists: compiled with localedef into ``folder``."""
    if shutil.which("localedef") is None:
        pytest.skip("localedef is needed to compile the test locales")
    language, charset = name.split(".")
    done = subprocess.run(["localedef", "-i", language, "-f", charset, str(folder / name)],
                          capture_output=True, text=True, timeout=120)
    if not (folder / name).is_dir():
        pytest.skip(f"localedef cannot compile {name}: {done.stderr.strip()[:200]}")
    return {**os.environ, "LOCPATH": str(folder)}


def run(driver, lines: list[str], locale: str = "C", env: dict | None = None) -> list[str]:
    exe, _ = driver
    done = subprocess.run([str(exe), locale], input="".join(f"{x}\n" for x in lines),
                          capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stderr
    out = done.stdout.splitlines()
    assert len(out) == len(lines)
    return out


def bits(x: float) -> str:
    return f"{struct.unpack('<Q', struct.pack('<d', x))[0]:016x}"


def doubles() -> list[float]:
    """Every exponent's doubles by random bits, ordinary magnitudes, and the edges."""
    rng = random.Random(20261202)
    out = [struct.unpack("<d", struct.pack("<Q", rng.getrandbits(64)))[0] for _ in range(1500)]
    out += [rng.uniform(-1e3, 1e3) for _ in range(500)]
    out += [0.0, -0.0, 0.1, 0.3, 1e-5, 1e-4, 1.5, 2.5e16, 1e16, 1e15, 123456.0, 1234567.0,
            9.9996, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, 1e22, 1 / 3]
    return [x for x in out if x == x and abs(x) != float("inf")]


def check_numbers(driver, locale="C", env=None):
    xs = doubles()
    rng = random.Random(7)
    ns = [rng.randint(0, 17) for _ in xs]
    lines = ([f"r {bits(x)}" for x in xs]
             + [f"g {n} {bits(x)}" for n, x in zip(ns, xs, strict=True)])
    out = run(driver, lines, locale, env)
    shortest, general = out[: len(xs)], out[len(xs):]
    for x, text in zip(xs, shortest, strict=True):
        # reads back to x, with repr's digits: the same decimal value as repr's text
        assert float(text) == x and Decimal(text) == Decimal(repr(x)), (locale, repr(x), text)
    for x, n, text in zip(xs, ns, general, strict=True):
        assert text == f"{x:.{max(n, 1)}g}", (locale, repr(x), n, text)
    specials = run(driver, [f"r {bits(v)}" for v in (float("nan"), float("inf"), -float("inf"))]
                   + [f"g 3 {bits(v)}" for v in (float("inf"), -0.0)], locale, env)
    assert specials == ["nan", "inf", "-inf", "inf", "-0"]


def test_numbers_are_the_shortest_round_trip_and_n_digits(driver):
    check_numbers(driver)


@pytest.mark.parametrize("locale", LOCALES)
def test_numbers_are_the_same_in_another_locale(driver, locale):
    env = compiled_locale(driver[1], locale)
    # the locale is in effect: C's own %g writes its separator
    probe = subprocess.run(["sh", "-c", f"LC_ALL={locale} locale decimal_point"],
                           capture_output=True, text=True, env=env, timeout=60)
    assert probe.stdout.strip() not in ("", "."), probe.stdout + probe.stderr
    check_numbers(driver, locale, env)


@pytest.mark.parametrize("locale", ("C", *LOCALES))
def test_the_other_conversions_and_the_buffer_form(driver, locale):
    env = compiled_locale(driver[1], locale) if locale != "C" else None
    out = run(driver, ["m", "p", "P", f"f 64 {bits(0.1)}", f"f 4 {bits(0.1)}", f"f 1 {bits(0.1)}"],
              locale, env)
    assert out[0] == "[ab|  -42|7  |12|-5|ff|z|%|'a\\'b\\x01\u00e9'|xy|   9]"
    # a conversion it does not have (printf's %f and %g) ends the text, visibly
    assert out[1:3] == ["before %f", "before %g"]
    assert out[3:] == ["x=0.1;|6", "x=0|6", "|6"]  # truncated with its NUL, full length back


#: printf's floating conversions (they follow LC_NUMERIC and are not the shortest round trip).
FLOATING = re.compile(r'"[^"\n]*%[-+ #0-9.*]*[lL]?[fFeEgGaA][^"\n]*"')


def test_no_message_uses_printf_floating_conversions():
    found = []
    for path in sorted(SOURCE.glob("*/*.c")):
        if path.name == "text.c":  # text.c: %e is its digit source
            continue
        code = re.sub(r"/\*.*?\*/", "", path.read_text(encoding="utf-8"), flags=re.S)
        found += [f"{path.name}: {m.group(0)}" for m in FLOATING.finditer(code)]
    assert found == []
