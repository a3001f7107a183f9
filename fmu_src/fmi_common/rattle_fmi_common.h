/*
 * rattle_fmi_common.h - what every FMI layer of these FMUs does the same way, of no FMI version,
 * written once, in a folder of its own (fmu_src/fmi_common/): the status shim of the
 * pythonfmu FMUs (rattle_fmi_shim.c), the FMI 2.0 face (fmi2_functions.c, with what FMI 2.0
 * layers share: rattle_fmi2_common.c) and the FMI 3.0 face (fmu_src/fmi3/fmi3_functions.c)
 * compile rattle_fmi_common.c, with the model library's
 * operating-system layer (rattle_model/portable.c: UTF-8, files).  It includes no FMI
 * header: the words of a message that differ between FMI versions (the names of the calls,
 * the standard's section) are the caller's.
 *
 * Serialized FMU states: an envelope of RATTLE_STATE_HEADER bytes, then the unit's state (the
 * model library's record, rm_save).  Little-endian:
 *   0  8  "RTLSTSER"
 *   8  4  envelope version (RATTLE_STATE_ENVELOPE_VERSION)
 *  12  4  0 (reserved)
 *  16  8  payload length n
 *  24  8  FNV-1a 64 of the payload
 *  32 64  the FMU's GUID (FMI 3.0: its instantiation token), NUL-padded
 *  96  n  payload
 * The host's buffer may be larger than the reported size (FMI 2.0 and 3.0 allow it): the rest
 * is zeroed and ignored when the state is read back.
 */
#ifndef RATTLE_FMI_COMMON_H
#define RATTLE_FMI_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "rm_portable.h" /* UTF-8 and files: the model library's, compiled in */

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
/* An FMU state of the native faces: the unit's record (rm_save) behind its tag, on the list of
 * the instance that made it (freeing the instance frees its states). */
typedef struct RattleRecordState RattleRecordState;
struct RattleRecordState {
    RattleStateTag tag; /* first: the host's pointer is checked through it */
    unsigned char* record;
    size_t size;
    RattleRecordState** list; /* the head of the making instance's list */
    RattleRecordState* next;
    RattleRecordState* prev;
};
/* `record` (malloc'ed, taken over) into `reuse` (its old record freed) or, where reuse is NULL,
 * into a new state of the FMU `guid` at the head of *list, stored in *made: 1, or 0 out of
 * memory (the record freed, nothing changed). */
RATTLE_INTERNAL int rattle_record_state_keep(RattleRecordState** list, RattleRecordState* reuse,
                                            RattleRecordState** made, unsigned char* record,
                                            size_t size, const char* guid);
/* Takes the state off its instance's list, clears its tag and frees it with its record. */
RATTLE_INTERNAL void rattle_record_state_delete(RattleRecordState* st);
/* 1 when `address`, which the host passed as the address of its FMU-state variable
 * (fmi2FMUstate*, fmi3FMUState*), points at a state of these FMUs itself: the host passed the
 * state where FMI asks for its address (fmusim of Reference-FMUs 0.0.39 does, when it frees
 * the state of a state file).  Reading there is safe either way (the host's pointer variable
 * or the state), and the tag's first bytes are never those of a pointer on x86-64 (not a
 * canonical address); `address` NULL gives 0. */
RATTLE_INTERNAL int rattle_state_misaddressed(const void* address);
#define RATTLE_STATE_MISADDRESSED                                                              \
    "points to an FMU state, not to the host's variable that holds one (FMI asks for its "     \
    "address, &state)"
/* 1 when `state` (an FMU state pointer from the host) carries the tag of the FMU `guid` (""
 * when the FMU has none); else 0 with the refusal in why.  `makers` names the calls that make
 * states ("fmi2GetFMUstate or fmi2DeSerializeFMUstate"). */
RATTLE_INTERNAL int rattle_state_check(const void* state, const char* guid, const char* makers,
                                       char* why, size_t why_size);

/* 1 when a state of n payload bytes fits a buffer of `size` bytes; else 0 with the refusal's
 * text in why; `size_call` names the call that tells the size ("fmi2SerializedFMUstateSize"). */
RATTLE_INTERNAL int rattle_state_room(size_t size, size_t n, const char* size_call, char* why,
                                      size_t why_size);
/* Writes the envelope around the n payload bytes already at out + RATTLE_STATE_HEADER and
 * zeroes the rest of the `size` bytes (rattle_state_room(size, n) must hold). */
RATTLE_INTERNAL void rattle_state_seal(unsigned char* out, size_t size, size_t n,
                                       const char* guid);
/* 1 with the payload length in *n when the `size` bytes at `in` are an intact state of the
 * FMU `guid`; else 0 with the refusal's text in why. */
RATTLE_INTERNAL int rattle_state_open(const unsigned char* in, size_t size, const char* guid,
                                     uint64_t* n, char* why, size_t why_size);

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

/* The instance name every instantiation function checks: non-blank (FMI 2.0 and 3.0 ask for
 * it) and UTF-8.  1, or 0 with the refusal in why ("... allowed: a non-empty string (<rule>)",
 * `rule` citing the standard); `name` gets a printable copy of instanceName either way. */
RATTLE_INTERNAL int rattle_check_instance_name(const char* instanceName, const char* rule,
                                               char* name, size_t name_size, char* why,
                                               size_t why_size);
/* The token the master read from the modelDescription (`what`: "GUID", "instantiationToken")
 * against the FMU's own `expected` (no check when that is ""): 1, or 0 with "<what> <given>
 * does not match this FMU's <expected>" in why. */
RATTLE_INTERNAL int rattle_check_token(const char* given, const char* expected,
                                       const char* what, char* why, size_t why_size);

/* The file system, for the resources folder (paths are UTF-8; the reading is rm_portable.h's,
 * the library's own). */
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

/* The file in a native FMU's resources folder that names the FMU: its model identifier on the
 * first line (the counterpart of pythonfmu's slavemodule.txt). */
#define RATTLE_RESOURCE_MARKER "model_identifier.txt"
/* The longest resources folder accepted: the model library joins speed-table paths to it. */
#define RATTLE_MAX_RESOURCES_PATH_BYTES 4032
/* The canonical path of the resources folder of the native FMU `identifier` that `location`
 * (not NULL) names (malloc'ed): decoded (rattle_location_to_path), existing, a folder holding
 * RATTLE_RESOURCE_MARKER that names `identifier` (read only when it is a regular file).  NULL
 * with the reason in why ("names '<path>', which has no model_identifier.txt: ..."). */
RATTLE_INTERNAL char* rattle_resources_folder(const char* location, const char* identifier,
                                              char* why, size_t why_size);

/* The log category of a status (0 OK .. 4 Fatal, the numbers of fmi2Status and fmi3Status;
 * the modelDescription's <LogCategories>). */
RATTLE_INTERNAL const char* rattle_status_category(int status);

#endif
