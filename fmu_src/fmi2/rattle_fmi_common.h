/*
 * rattle_fmi_common.h - what both FMI layers do the same way, written once: the status shim of
 * the pythonfmu FMUs (rattle_fmi_shim.c) and the FMI 2.0 glue of the native FMUs
 * (fmi2_functions.c) both compile rattle_fmi_common.c.
 *
 * Serialized FMU states: an envelope of RATTLE_STATE_HEADER bytes, then the unit's state (the
 * model library's record, rm_save).  Little-endian:
 *   0  8  "RTLSTSER"
 *   8  4  envelope version (RATTLE_STATE_ENVELOPE_VERSION)
 *  12  4  0 (reserved)
 *  16  8  payload length n
 *  24  8  FNV-1a 64 of the payload
 *  32 64  the FMU's GUID, NUL-padded
 *  96  n  payload
 * The host's buffer may be larger than the reported size (FMI 2.0 allows it): the rest is
 * zeroed and ignored when the state is read back.
 */
#ifndef RATTLE_FMI_COMMON_H
#define RATTLE_FMI_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "fmi2Functions.h"

/* Internal to the FMU's binary: never exported to the host (nor interposed by a namesake). */
#if defined(__GNUC__) && !defined(_WIN32)
#define RATTLE_INTERNAL __attribute__((visibility("hidden")))
#else
#define RATTLE_INTERNAL
#endif

#define RATTLE_STATE_SERIAL_MAGIC "RTLSTSER"
#define RATTLE_STATE_ENVELOPE_VERSION 1u
#define RATTLE_STATE_HEADER 96u

/* The identity at the start of every FMU state these FMUs hand out, laid out alike in both
 * flavours, so that states of either are told apart by their GUID. */
typedef struct {
    char magic[8];
    char guid[64];
} RattleStateTag;
RATTLE_INTERNAL void rattle_state_tag(RattleStateTag* tag, const char* guid);
/* Clears the tag of a state about to be freed (a dangling pointer then fails the check). */
RATTLE_INTERNAL void rattle_state_untag(RattleStateTag* tag);
/* 1 when `state` (an fmi2FMUstate from the host) carries the tag of the FMU `guid` ("" when
 * the FMU has none); else 0 with the refusal in why. */
RATTLE_INTERNAL int rattle_state_is_ours(const void* state, const char* guid, char* why,
                                         size_t why_size);

/* 1 when a state of n payload bytes fits a buffer of `size` bytes; else 0 with the refusal's
 * text in why. */
RATTLE_INTERNAL int rattle_state_fits(size_t size, size_t n, char* why, size_t why_size);
/* Writes the envelope around the n payload bytes already at out + RATTLE_STATE_HEADER and
 * zeroes the rest of the `size` bytes (rattle_state_fits(size, n) must hold). */
RATTLE_INTERNAL void rattle_state_seal(unsigned char* out, size_t size, size_t n,
                                       const char* guid);
/* 1 with the payload length in *n when the `size` bytes at `in` are an intact state of the
 * FMU `guid`; else 0 with the refusal's text in why. */
RATTLE_INTERNAL int rattle_state_open(const unsigned char* in, size_t size, const char* guid,
                                     uint64_t* n, char* why, size_t why_size);

/* UTF-8 as Python's decoder accepts it (RFC 3629: no overlong forms, no surrogates, at most
 * U+10FFFF).  rattle_utf8_decode decodes one code point at s (n bytes available) and returns
 * its length, 0 if not UTF-8; `surrogates` accepts the 3-byte forms of U+D800..U+DFFF (WTF-8,
 * used internally for the lone surrogates json.loads can produce). */
RATTLE_INTERNAL size_t rattle_utf8_decode(const unsigned char* s, size_t n, unsigned* cp,
                                          int surrogates);
/* Offset of the first byte that is not valid UTF-8, or (size_t)-1 if all are. */
RATTLE_INTERNAL size_t rattle_utf8_error_at_n(const char* text, size_t n);
RATTLE_INTERNAL size_t rattle_utf8_error_at(const char* text);
/* A copy of `text` for messages: bytes that are not UTF-8 become '?', at most `size` - 1. */
RATTLE_INTERNAL void rattle_printable(char* out, size_t size, const char* text);

/* An absolute path: "/..." (on Windows also "C:\\...", "C:/...", "\\\\server\\..."). */
RATTLE_INTERNAL int rattle_path_is_absolute(const char* path);
/* The local path a resource location names (malloc'ed), or NULL with the reason in why:
 * "file:///p", "file://localhost/p", "file:/p" with every %XX decoded (%00 refused; a
 * malformed escape stays literal; '?' and '#' belong to the path), or an absolute path taken
 * as it is. */
RATTLE_INTERNAL char* rattle_location_to_path(const char* location, char* why,
                                              size_t why_size);

/* fmi2Instantiate's argument checks that both FMI layers make: instanceName (non-blank,
 * UTF-8), fmuType (co-simulation only) and fmuGUID (equal to `guid`, unless that is "").  1,
 * or 0 with the refusal in why; `name` gets a printable copy of instanceName either way. */
RATTLE_INTERNAL int rattle_check_instantiate(const char* instanceName, int fmuType,
                                             const char* fmuGUID, const char* guid, char* name,
                                             size_t name_size, char* why, size_t why_size);

/* The file system, for the resources folder (paths are UTF-8; on Windows converted to the
 * wide-character API). */
/* The canonical absolute path of an existing file or folder (malloc'ed), or NULL with the
 * reason ("no such file or directory", ...) in why. */
RATTLE_INTERNAL char* rattle_canonical_path(const char* path, char* why, size_t why_size);
RATTLE_INTERNAL int rattle_is_dir(const char* path);
RATTLE_INTERNAL int rattle_is_regular_file(const char* path);
/* The first line of the marker file `path` (a small text file naming the FMU, such as
 * resources/model_identifier.txt), without its line end, in out (at most size - 1 bytes).
 * Read only when it is a regular file: it is opened non-blocking and checked again on the
 * open descriptor, so that a FIFO or a device there is refused without blocking or reading it.
 * RATTLE_MARKER_OK; RATTLE_MARKER_MISSING when nothing is there; RATTLE_MARKER_BAD with the
 * reason in why ("is a FIFO, not a regular file", ...). */
enum { RATTLE_MARKER_OK = 0, RATTLE_MARKER_MISSING = 1, RATTLE_MARKER_BAD = 2 };
RATTLE_INTERNAL int rattle_read_marker(const char* path, char* out, size_t size, char* why,
                                       size_t why_size);

/* The log category of a status (the modelDescription's <LogCategories>). */
RATTLE_INTERNAL const char* rattle_status_category(int status);
/* A refusal of fmi2Instantiate to the host's logger, before any instance exists:
 * "<prefix>fmi2Instantiate: <message>", passed verbatim (never as a format string). */
RATTLE_INTERNAL void rattle_instantiate_log(const fmi2CallbackFunctions* functions,
                                            const char* name, fmi2Status status,
                                            const char* prefix, const char* fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* The refusals of what these FMUs do not provide (the modelDescription says so). */
#define RATTLE_NO_DIRECTIONAL_DERIVATIVES                                                      \
    "not provided by this FMU (providesDirectionalDerivative = false)"
#define RATTLE_NO_INPUT_DERIVATIVES                                                            \
    "not provided by this FMU (canInterpolateInputs = false): set pinion.a as an input "      \
    "instead; nothing stored"
#define RATTLE_NO_OUTPUT_DERIVATIVES "not provided by this FMU (maxOutputDerivativeOrder = 0)"
#define RATTLE_NO_ASYNCHRONOUS_STEP                                                            \
    "no asynchronous step to cancel: every fmi2DoStep of this FMU completes within the call "  \
    "(canRunAsynchronuously = false)"
/* The refusal of a status inquiry that FMI 2.0 does not define for the function called, or
 * that only means something after fmi2Pending (never returned): `allowed` names what is. */
RATTLE_INTERNAL void rattle_status_refusal(char* why, size_t why_size, int kind,
                                           const char* allowed);

#endif
