/* rattle_fmi_common.c - see rattle_fmi_common.h. */
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* realpath under -std=c99 */
#endif
#if defined(_WIN32) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1
#endif

#include "rattle_fmi_common.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <windows.h>
#endif

/* ------------------------------------------------------------------ the state envelope */
static uint64_t fnv1a64(const unsigned char* p, size_t n)
{
    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static void put_le(unsigned char* p, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static uint64_t get_le(const unsigned char* p, int bytes)
{
    uint64_t v = 0;
    for (int i = bytes - 1; i >= 0; i--) v = (v << 8) | p[i];
    return v;
}

#define STATE_MAGIC "RTLSTATE"

void rattle_state_tag(RattleStateTag* tag, const char* guid)
{
    memcpy(tag->magic, STATE_MAGIC, 8);
    snprintf(tag->guid, sizeof tag->guid, "%s", guid);
}

void rattle_state_untag(RattleStateTag* tag) { memset(tag->magic, 0, sizeof tag->magic); }

int rattle_record_state_keep(RattleRecordState** list, RattleRecordState* reuse,
                             RattleRecordState** made, unsigned char* record, size_t size,
                             const char* guid)
{
    if (reuse != NULL) {
        free(reuse->record);
        reuse->record = record;
        reuse->size = size;
        return 1;
    }
    RattleRecordState* st = calloc(1, sizeof *st);
    if (st == NULL) {
        free(record);
        return 0;
    }
    rattle_state_tag(&st->tag, guid);
    st->record = record;
    st->size = size;
    st->list = list;
    st->next = *list;
    if (*list != NULL) (*list)->prev = st;
    *list = st;
    *made = st;
    return 1;
}

void rattle_record_state_delete(RattleRecordState* st)
{
    if (st->prev != NULL)
        st->prev->next = st->next;
    else
        *st->list = st->next;
    if (st->next != NULL) st->next->prev = st->prev;
    rattle_state_untag(&st->tag);
    free(st->record);
    free(st);
}

int rattle_state_misaddressed(const void* address)
{
    /* no more bytes than a pointer variable has */
    size_t n = sizeof(void*) < 8 ? sizeof(void*) : 8;
    return address != NULL && memcmp(address, STATE_MAGIC, n) == 0;
}

int rattle_state_check(const void* state, const char* guid, const char* makers, char* why,
                       size_t why_size)
{
    const RattleStateTag* tag = state;
    if (tag == NULL) {
        snprintf(why, why_size, "the FMU state is NULL");
        return 0;
    }
    if (memcmp(tag->magic, STATE_MAGIC, 8) != 0) {
        snprintf(why, why_size, "not an FMU state of this FMU (made by %s of %s); nothing "
                 "changed", makers, guid[0] ? guid : "this FMU");
        return 0;
    }
    if (strncmp(tag->guid, guid, sizeof tag->guid) != 0) {
        char other[sizeof tag->guid + 1], shown[80];
        memcpy(other, tag->guid, sizeof tag->guid);
        other[sizeof tag->guid] = '\0';
        rattle_printable(shown, sizeof shown, other);
        snprintf(why, why_size, "the FMU state belongs to the FMU with GUID %s, not to this one "
                 "(%s); nothing changed", shown, guid);
        return 0;
    }
    return 1;
}

int rattle_state_room(size_t size, size_t n, const char* size_call, char* why, size_t why_size)
{
    if (size >= RATTLE_STATE_HEADER && size - RATTLE_STATE_HEADER >= n) return 1;
    snprintf(why, why_size, "the buffer of %zu bytes is too small: this state needs %zu bytes "
             "(%s); nothing written", size, (size_t)(RATTLE_STATE_HEADER + n), size_call);
    return 0;
}

void rattle_state_seal(unsigned char* out, size_t size, size_t n, const char* guid)
{
    size_t guid_length = strlen(guid) < 63 ? strlen(guid) : 63;
    memset(out, 0, RATTLE_STATE_HEADER);
    memcpy(out, RATTLE_STATE_SERIAL_MAGIC, 8);
    put_le(out + 8, RATTLE_STATE_ENVELOPE_VERSION, 4);
    put_le(out + 16, n, 8);
    put_le(out + 24, fnv1a64(out + RATTLE_STATE_HEADER, n), 8);
    memcpy(out + 32, guid, guid_length);
    memset(out + RATTLE_STATE_HEADER + n, 0, size - RATTLE_STATE_HEADER - n);
}

int rattle_state_open(const unsigned char* in, size_t size, const char* guid, uint64_t* n,
                      char* why, size_t why_size)
{
    if (size < RATTLE_STATE_HEADER || memcmp(in, RATTLE_STATE_SERIAL_MAGIC, 8) != 0) {
        snprintf(why, why_size, "the %zu bytes are not a serialized state of a drive-rattle "
                 "FMU (no \"" RATTLE_STATE_SERIAL_MAGIC "\" header); nothing changed", size);
        return 0;
    }
    uint64_t version = get_le(in + 8, 4);
    if (version != RATTLE_STATE_ENVELOPE_VERSION) {
        snprintf(why, why_size, "the serialized state has envelope version %llu; this FMU "
                 "reads version %u; nothing changed", (unsigned long long)version,
                 RATTLE_STATE_ENVELOPE_VERSION);
        return 0;
    }
    char found[65];
    memcpy(found, in + 32, 64);
    found[64] = '\0';
    if (strcmp(found, guid) != 0) {
        char shown[80];
        rattle_printable(shown, sizeof shown, found);
        snprintf(why, why_size, "the serialized state belongs to the FMU with GUID %s, not to "
                 "this one (%s); nothing changed", shown, guid);
        return 0;
    }
    *n = get_le(in + 16, 8);
    if (*n > size - RATTLE_STATE_HEADER) {
        snprintf(why, why_size, "the serialized state is truncated: %zu bytes, its header "
                 "announces %llu; nothing changed", size,
                 (unsigned long long)(RATTLE_STATE_HEADER + *n));
        return 0;
    }
    if (fnv1a64(in + RATTLE_STATE_HEADER, (size_t)*n) != get_le(in + 24, 8)) {
        snprintf(why, why_size, "the serialized state is corrupt (checksum mismatch); nothing "
                 "changed");
        return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------ UTF-8 */
void rattle_printable(char* out, size_t size, const char* text)
{
    size_t j = 0, left = strlen(text);
    const char* p = text;
    while (left > 0 && j + 1 < size) {
        /* only what can still be copied is checked (a character of up to 4 bytes beyond it
         * is cut there anyway): linear in the output, however long the text */
        size_t room = size - 1 - j, span = left < room + 3 ? left : room + 3;
        size_t bad = rm_utf8_error_at((const unsigned char*)p, span);
        if (bad == 0) {
            out[j++] = '?';
            p++;
            left--;
            continue;
        }
        size_t good = bad == (size_t)-1 ? span : bad;
        if (good > room) good = room;
        memcpy(out + j, p, good);
        j += good;
        p += good;
        left -= good;
    }
    out[j] = '\0';
}

/* ------------------------------------------------------------------ resource location */
static char* copy_string(const char* s)
{
    size_t n = strlen(s) + 1;
    char* p = malloc(n);
    if (p != NULL) memcpy(p, s, n);
    return p;
}

int rattle_path_is_absolute(const char* path)
{
#if defined(_WIN32)
    if ((path[0] == '\\' && path[1] == '\\') || (path[0] == '/' && path[1] == '/')) return 1;
    return ((path[0] >= 'A' && path[0] <= 'Z') || (path[0] >= 'a' && path[0] <= 'z'))
           && path[1] == ':' && (path[2] == '\\' || path[2] == '/');
#else
    return path[0] == '/';
#endif
}

static int hex_value(char ch)
{
    if (ch >= '0' && ch <= '9') return ch - '0';
    if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
    return -1;
}

static int prefix_nocase(const char* s, const char* prefix)
{
    for (; *prefix != '\0'; s++, prefix++) {
        char a = *s, b = *prefix;
        if (a >= 'A' && a <= 'Z') a = (char)(a - 'A' + 'a');
        if (a != b) return 0;
    }
    return 1;
}

/* The local path a resource location names (malloc'ed), or NULL with the reason: "file:///p",
 * "file://localhost/p", "file:/p" with every %XX decoded (%00 refused), or an absolute path
 * taken as it is (on Windows "file:///C:/p" is C:/p). */
char* rattle_location_to_path(const char* location, char* why, size_t why_size)
{
    const char* p;
    char* out;
    char* q;
    size_t scheme = 0;
    if (prefix_nocase(location, "file:")) {
        p = location + 5;
        if (p[0] == '/' && p[1] == '/') {
            p += 2;
            if (prefix_nocase(p, "localhost/"))
                p += 9;
            else if (p[0] != '/') {
                snprintf(why, why_size, "names a file on another host; allowed: a local "
                                        "file:// URI or an absolute path");
                return NULL;
            }
        }
        if (p[0] != '/') {
            snprintf(why, why_size, "is a relative file URI; allowed: file:///<absolute path>");
            return NULL;
        }
#if defined(_WIN32)
        if (((p[1] >= 'A' && p[1] <= 'Z') || (p[1] >= 'a' && p[1] <= 'z')) && p[2] == ':')
            p++; /* /C:/... */
#endif
    }
    else {
        while ((location[scheme] >= 'a' && location[scheme] <= 'z')
               || (location[scheme] >= 'A' && location[scheme] <= 'Z')
               || (scheme > 0 && ((location[scheme] >= '0' && location[scheme] <= '9')
                                  || location[scheme] == '+' || location[scheme] == '-'
                                  || location[scheme] == '.')))
            scheme++;
        if (scheme > 1 && location[scheme] == ':') {
            snprintf(why, why_size, "has the URI scheme '%.*s', which this FMU cannot read; "
                                    "allowed: file:// URIs and absolute paths",
                     (int)(scheme > 32 ? 32 : scheme), location);
            return NULL;
        }
        if (!rattle_path_is_absolute(location)) {
            snprintf(why, why_size, "is %s; allowed: a file:// URI or an absolute path",
                     location[0] == '\0' ? "empty" : "a relative path");
            return NULL;
        }
        return copy_string(location);
    }
    out = malloc(strlen(p) + 1);
    if (out == NULL) {
        snprintf(why, why_size, "cannot be decoded: out of memory");
        return NULL;
    }
    for (q = out; *p != '\0'; p++) {
        int hi, lo;
        if (p[0] == '%' && (hi = hex_value(p[1])) >= 0 && (lo = hex_value(p[2])) >= 0) {
            if ((hi | lo) == 0) {
                free(out);
                snprintf(why, why_size, "holds %%00, which no path can contain");
                return NULL;
            }
            *q++ = (char)(hi * 16 + lo);
            p += 2;
        }
        else
            *q++ = *p;
    }
    *q = '\0';
    return out;
}

/* ------------------------------------------------------------------ files */
char* rattle_canonical_path(const char* path, char* why, size_t why_size)
{
#if defined(_WIN32)
    wchar_t* w = rm_widen(path);
    wchar_t* full;
    char* out = NULL;
    int n;
    if (w == NULL) {
        snprintf(why, why_size, "cannot be opened: %s", rm_errno_reason(ENOENT));
        return NULL;
    }
    full = _wfullpath(NULL, w, 0);
    free(w);
    if (full == NULL) {
        snprintf(why, why_size, "cannot be opened: %s", rm_errno_reason(errno));
        return NULL;
    }
    n = WideCharToMultiByte(CP_UTF8, 0, full, -1, NULL, 0, NULL, NULL);
    if (n > 0 && (out = malloc((size_t)n)) != NULL)
        WideCharToMultiByte(CP_UTF8, 0, full, -1, out, n, NULL, NULL);
    free(full);
    if (out == NULL || rm_path_kind(out) == RM_PATH_MISSING) {
        snprintf(why, why_size, "cannot be opened: %s", rm_errno_reason(ENOENT));
        free(out);
        return NULL;
    }
    return out;
#else
    char* real = realpath(path, NULL);
    if (real == NULL) snprintf(why, why_size, "cannot be opened: %s", rm_errno_reason(errno));
    return real;
#endif
}

int rattle_is_dir(const char* path) { return rm_path_kind(path) == RM_PATH_DIRECTORY; }

int rattle_is_regular_file(const char* path) { return rm_path_kind(path) == RM_PATH_REGULAR; }

int rattle_read_marker(const char* path, char* out, size_t size, char* why, size_t why_size)
{
    RmFileProblem problem;
    size_t n;
    char* text;
    if (size == 0) {
        snprintf(why, why_size, "cannot be read: no room for it");
        return RATTLE_MARKER_BAD;
    }
    text = rm_read_small_file(path, size - 1, 1, &n, &problem);
    out[0] = '\0';
    if (text == NULL) {
        if (problem.problem == RM_FILE_MISSING) return RATTLE_MARKER_MISSING;
        if (problem.problem == RM_FILE_NOT_REGULAR)
            snprintf(why, why_size, "is %s, not a regular file", problem.reason);
        else
            snprintf(why, why_size, "cannot be read: %s", problem.reason);
        return RATTLE_MARKER_BAD;
    }
    memcpy(out, text, n + 1);
    free(text);
    out[strcspn(out, "\r\n")] = '\0';
    return RATTLE_MARKER_OK;
}

/* ------------------------------------------------------------------ instantiation */
int rattle_check_instance_name(const char* instanceName, const char* rule, char* name,
                               size_t name_size, char* why, size_t why_size)
{
    size_t bad;
    name[0] = '\0';
    if (instanceName == NULL || instanceName[strspn(instanceName, " \t\r\n")] == '\0') {
        snprintf(why, why_size, "instanceName is %s; allowed: a non-empty string (%s)",
                 instanceName == NULL ? "NULL" : "blank", rule);
        return 0;
    }
    rattle_printable(name, name_size, instanceName);
    bad = rm_utf8_string_error_at(instanceName);
    if (bad != (size_t)-1) {
        snprintf(why, why_size, "instanceName '%s' is not valid UTF-8 (byte 0x%02X at offset "
                 "%zu); allowed: UTF-8 text", name, (unsigned)(unsigned char)instanceName[bad],
                 bad);
        return 0;
    }
    return 1;
}

int rattle_check_token(const char* given, const char* expected, const char* what, char* why,
                       size_t why_size)
{
    char shown[128];
    if (expected[0] == '\0' || (given != NULL && strcmp(given, expected) == 0)) return 1;
    rattle_printable(shown, sizeof shown, given != NULL ? given : "(null)");
    snprintf(why, why_size, "%s %s does not match this FMU's %s", what, shown, expected);
    return 0;
}

#if defined(_WIN32)
#define SEP "\\"
#else
#define SEP "/"
#endif

char* rattle_resources_folder(const char* location, const char* identifier, char* why,
                              size_t why_size)
{
    char shown[256], found_identifier[256], reason[256];
    char* decoded;
    char* real;
    char* marker;
    size_t n;
    int found;
    decoded = rattle_location_to_path(location, why, why_size);
    if (decoded == NULL) return NULL;
    rattle_printable(shown, sizeof shown, decoded);
    real = rattle_canonical_path(decoded, reason, sizeof reason);
    free(decoded);
    if (real == NULL || !rattle_is_dir(real)) {
        snprintf(why, why_size, "names '%s', which %s; allowed: this FMU's resources folder",
                 shown, real == NULL ? reason : "is not a folder");
        free(real);
        return NULL;
    }
    rattle_printable(shown, sizeof shown, real);
    n = strlen(real);
    if (n > RATTLE_MAX_RESOURCES_PATH_BYTES) {
        snprintf(why, why_size, "names a path of %zu bytes; allowed: at most %d", n,
                 RATTLE_MAX_RESOURCES_PATH_BYTES);
        free(real);
        return NULL;
    }
    marker = malloc(n + sizeof SEP "resources" SEP RATTLE_RESOURCE_MARKER);
    if (marker == NULL) {
        snprintf(why, why_size, "cannot be read: out of memory");
        free(real);
        return NULL;
    }
    sprintf(marker, "%s" SEP RATTLE_RESOURCE_MARKER, real);
    found = rattle_read_marker(marker, found_identifier, sizeof found_identifier, reason,
                               sizeof reason);
    if (found == RATTLE_MARKER_MISSING) {
        sprintf(marker, "%s" SEP "resources" SEP RATTLE_RESOURCE_MARKER, real);
        if (rattle_is_regular_file(marker))
            snprintf(why, why_size, "names '%s', the folder the FMU was unpacked to; allowed: "
                     "its resources folder, '%s" SEP "resources'", shown, shown);
        else
            snprintf(why, why_size, "names '%s', which has no " RATTLE_RESOURCE_MARKER ": not "
                     "the resources folder of this FMU", shown);
    }
    else if (found == RATTLE_MARKER_BAD)
        snprintf(why, why_size, "names '%s', whose " RATTLE_RESOURCE_MARKER " %s: not the "
                 "resources folder of this FMU", shown, reason);
    else if (strcmp(found_identifier, identifier) != 0) {
        char other[64];
        rattle_printable(other, sizeof other, found_identifier);
        snprintf(why, why_size, "names '%s', the resources of FMU '%s', not of %s", shown,
                 other, identifier);
        found = RATTLE_MARKER_BAD;
    }
    free(marker);
    if (found != RATTLE_MARKER_OK) {
        free(real);
        return NULL;
    }
    return real;
}

/* ------------------------------------------------------------------ logging */
const char* rattle_status_category(int status)
{
    switch (status) {
    case 0: return "logAll";
    case 1: return "logStatusWarning";
    case 2: return "logStatusDiscard";
    case 3: return "logStatusError";
    default: return "logStatusFatal";
    }
}
