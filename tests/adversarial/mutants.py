"""Defects injected into the model library's sources (patched copies: variants.py builds FMUs
of both flavours from them), which the boundary rows and the fuzzer must catch.  Each is a
defect they once let pass: the fuzzer passed a doStep that refused every valid step, and
row 12 a NaN output.  Each is a list of variants.Patch; the patched text must exist exactly
once."""

from __future__ import annotations

#: The three defects: name -> (patches, what it does).
MUTANTS = {
    "refuse-every-step": (
        [("unit.c",
          "            int ok = check_inputs(u, u->values, &err) && u->cls->step(u, t, h, "
          "&warning, &err);",
          "            int ok = (rm_puts(&err, \"every step refused (a mutant)\"), 0);")],
        "doStep refuses every step, valid ones included (with a message)"),
    "nan-output-ok": (
        [("unit.c",
          "        case RM_REAL: ((double*)out)[i] = x != NULL ? x->r : NAN; break;",
          "        case RM_REAL: ((double*)out)[i] = x != NULL && !(u->phase == RM_STEPPING\n"
          "                      && vr[i] == u->first_output) ? x->r : NAN; break;")],
        "while stepping, a get answers the first output as NaN with fmi2OK"),
    "half-applied-set": (
        [("unit.c",
          "                refused = 1;\n            }\n        }\n    }\n    if (refused) {",
          "                refused = 1;\n            }\n        }\n"
          "        if (!refused && type == RM_REAL)\n"
          "            u->values[vr[i]].r = ((const double*)values)[i];\n"
          "    }\n    if (refused) {")],
        "fmi2SetReal stores the entries before a bad one, then refuses the call"),
}

#: Defects only a sanitizer sees (tests/sanitize): the C is wrong, the answers are right.
SANITIZER_MUTANTS = {
    "leak": (
        [("unit.c",
          "    if (buf != NULL && capacity >= w.len) memcpy(buf, w.data, w.len);\n"
          "    free(w.data);",
          "    if (buf != NULL && capacity >= w.len) memcpy(buf, w.data, w.len);")],
        "rm_save leaks its buffer"),
    "overflow": (
        [("unit.c",
          "    char* p = malloc(n);\n    if (p != NULL) memcpy(p, s, n);",
          "    char* p = malloc(n - 1 > 0 ? n - 1 : 1);\n    if (p != NULL) memcpy(p, s, n);")],
        "a string's copy is written one byte past its allocation"),
}
